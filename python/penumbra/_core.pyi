"""Type stubs of the compiled core (``rust/penumbra-py``). Use the wrappers in
:mod:`penumbra`; this module is their implementation.

Every function here raises the classes of :mod:`penumbra.errors`:
``MeshError``, ``LightError``, ``CameraError``, ``SceneError`` and
``ParameterError`` (all ``InvalidInputError``, hence ``ValueError``) for bad
input; ``GpuUnavailableError`` when no adapter exists; ``GpuError`` when the
GPU fails; ``PenumbraIOError`` when a file cannot be written.
"""

from os import PathLike
from typing import Any, final

import numpy as np
import numpy.typing as npt

from penumbra.errors import CameraError as CameraError
from penumbra.errors import GpuError as GpuError
from penumbra.errors import GpuUnavailableError as GpuUnavailableError
from penumbra.errors import LightError as LightError
from penumbra.errors import MeshError as MeshError
from penumbra.errors import ParameterError as ParameterError
from penumbra.errors import PenumbraIOError as PenumbraIOError
from penumbra.errors import SceneError as SceneError

__all__ = [
    "adapter_info",
    "methods",
    "method_specs",
    "write_image",
    "Renderer",
    "__version__",
    "MeshError",
    "LightError",
    "CameraError",
    "SceneError",
    "ParameterError",
    "GpuUnavailableError",
    "GpuError",
    "PenumbraIOError",
]

__version__: str

def adapter_info() -> dict[str, Any]: ...
def methods() -> list[tuple[str, bool]]: ...
def method_specs() -> list[dict[str, Any]]: ...
def write_image(path: str | PathLike[str], image: npt.NDArray[np.float32]) -> None: ...
@final
class Renderer:
    def __new__(cls, timing: str = "auto", pass_cache: bool = True) -> Renderer: ...
    def adapter_info(self) -> dict[str, Any]: ...
    @property
    def pass_cache(self) -> bool: ...
    def pass_cache_entries(self) -> dict[str, int]: ...
    def clear_pass_cache(self) -> None: ...
    def pool_stats(self) -> dict[str, int]: ...
    def clear_pool(self) -> None: ...
    @property
    def timing_source(self) -> str: ...
    def render(
        self,
        meshes: list[
            tuple[
                str,
                npt.NDArray[np.float32],
                npt.NDArray[np.uint32],
                npt.NDArray[np.float32] | None,
                npt.NDArray[np.float32],
                int,
                npt.NDArray[np.float32],
            ]
        ],
        light: tuple[npt.NDArray[np.float32], float, npt.NDArray[np.float32]],
        camera: tuple[
            npt.NDArray[np.float32], npt.NDArray[np.float32], npt.NDArray[np.float32], float, int, int
        ],
        ambient: npt.NDArray[np.float32],
        method: str,
        params: dict[str, Any],
        intermediates: bool = False,
    ) -> dict[str, Any]: ...

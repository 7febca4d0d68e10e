"""Type stubs of the compiled core (``rust/penumbra-py``). Use the wrappers in
:mod:`penumbra`; this module is their implementation.

Every function here raises the classes of :mod:`penumbra.errors`:
``MeshError``, ``LightError``, ``CameraError``, ``SceneError`` and
``ParameterError`` (all ``InvalidInputError``, hence ``ValueError``) for bad
input, conversion errors included (never a bare ``TypeError``);
``GpuUnavailableError`` when no adapter exists; ``GpuFeatureError`` (a
``GpuUnavailableError``) when the adapter lacks a feature the method needs
(ray queries for ``raytraced``); ``GpuError`` when the GPU fails; ``PenumbraIOError`` when a file cannot be written; ``InternalError``
for a broken invariant of the core (a bug).

Scenes and cameras cross as the typed values of :mod:`penumbra.scene`
(``CoreScene``, ``CoreMesh``, ``CoreLight``, ``CoreCamera``), read by
attribute name.
"""

from os import PathLike
from typing import Any, final

import numpy as np
import numpy.typing as npt

from penumbra.errors import CameraError as CameraError
from penumbra.errors import GpuError as GpuError
from penumbra.errors import GpuFeatureError as GpuFeatureError
from penumbra.errors import GpuUnavailableError as GpuUnavailableError
from penumbra.errors import InternalError as InternalError
from penumbra.errors import LightError as LightError
from penumbra.errors import MeshError as MeshError
from penumbra.errors import ParameterError as ParameterError
from penumbra.errors import PenumbraIOError as PenumbraIOError
from penumbra.errors import SceneError as SceneError
from penumbra.scene import CoreCamera, CoreScene

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
    "GpuFeatureError",
    "PenumbraIOError",
    "InternalError",
]

__version__: str

def adapter_info() -> dict[str, Any]: ...
def methods() -> list[tuple[str, bool]]: ...
def method_specs() -> list[dict[str, Any]]: ...
def write_image(path: str | PathLike[str], image: npt.NDArray[np.float32]) -> None: ...
@final
class Renderer:
    # timing: "auto" (None) or "cpu"; pass_cache: a bool (None: True).
    def __new__(cls, timing: str | None = None, pass_cache: bool | None = None) -> Renderer: ...
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
        scene: CoreScene,
        camera: CoreCamera,
        method: str,
        params: dict[str, Any],
        intermediates: bool | None = None,
        outputs: list[str] | None = None,
    ) -> dict[str, Any]: ...

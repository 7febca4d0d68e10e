"""The renderer service and its results."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from penumbra import _core
from penumbra.errors import CameraError, ParameterError, SceneError
from penumbra.scene import Camera, Scene

__all__ = ["Renderer", "RenderResult", "adapter_info", "write_image", "methods"]


def adapter_info() -> dict[str, Any]:
    """The GPU adapter a renderer would use: name, backend, device type,
    driver, whether it has timestamp queries and whether it is software.

    Raises :class:`~penumbra.errors.GpuUnavailableError` when there is none."""
    return _core.adapter_info()


def methods(implemented_only: bool = True) -> list[str]:
    """Method names of SPEC section 4 (only those implemented, by default)."""
    return [name for name, done in _core.methods() if done or not implemented_only]


def write_image(path: str | os.PathLike[str], image: np.ndarray) -> None:
    """Writes a linear float image (H, W) or (H, W, 3) by extension: ``.png``
    sRGB-encoded 8-bit, ``.exr`` linear float, ``.npy`` the array as is."""
    path = os.fspath(path)
    array = np.asarray(image)
    if path.lower().endswith(".npy"):
        np.save(path, array)
        return
    _core.write_image(path, np.ascontiguousarray(array, dtype=np.float32))


@dataclass
class RenderResult:
    """One render: images by name (linear float32 numpy arrays; ``object_id``
    int32), per-pass ``timings`` in milliseconds and where they come from
    (``timing_source``: ``"gpu_timestamps"`` or ``"cpu_clock"``), and ``stats``
    that explain the cost."""

    method: str
    params: dict[str, Any]
    images: dict[str, np.ndarray]
    timings: dict[str, float]
    timing_source: str
    total_ms: float
    stats: dict[str, int] = field(default_factory=dict)

    @property
    def radiance(self) -> np.ndarray:
        """Linear radiance, float32 (H, W, 3)."""
        return self.images["radiance"]

    @property
    def visibility(self) -> np.ndarray:
        """Visible fraction of the light in [0, 1], float32 (H, W); 0 on background."""
        return self.images["visibility"]

    @property
    def depth(self) -> np.ndarray:
        """Distance along the camera axis, float32 (H, W); 0 on background."""
        return self.images["depth"]

    @property
    def normal(self) -> np.ndarray:
        """Unit shading normal, float32 (H, W, 3); 0 on background."""
        return self.images["normal"]

    @property
    def position(self) -> np.ndarray:
        """World position, float32 (H, W, 3); 0 on background."""
        return self.images["position"]

    @property
    def object_id(self) -> np.ndarray:
        """Object id, int32 (H, W); -1 on background."""
        return self.images["object_id"]

    @property
    def reused_passes(self) -> list[str]:
        """Passes whose cached outputs this render reused (they have no
        entry in ``timings``); empty without a pass cache."""
        prefix = "reused_"
        return [k[len(prefix):] for k, v in self.stats.items() if k.startswith(prefix) and k != "reused_passes" and v]

    def __getitem__(self, name: str) -> np.ndarray:
        return self.images[name]

    def save(self, path: str | os.PathLike[str], image: str = "radiance") -> None:
        """Writes one image (radiance by default) with :func:`write_image`."""
        if image not in self.images:
            raise ParameterError(f"no image named {image!r}; this result has {sorted(self.images)}")
        write_image(path, self.images[image])


class Renderer:
    """A long-lived render service: owns the GPU device and builds every
    pipeline once; renders release the GIL, so several Python threads may
    render on one renderer.

    ``timing="auto"`` times passes with GPU timestamps where the adapter has
    them (CPU clocks otherwise); ``"cpu"`` forces CPU clocks around each pass.

    ``pass_cache=True`` (the default) keeps the outputs of recent passes (the
    G-buffer, the centre shadow map, PVM's volume map, PVMF's mask and
    estimate), keyed by exactly the inputs each pass reads, and reuses them
    when a render's inputs for that pass are unchanged: changing only PVMF's
    ``n_blur`` reruns only the blur and shading. Results are bit-identical
    with and without it. A reused pass does not appear in ``timings`` (it did
    not run); ``stats["reused_passes"]`` counts them and
    ``stats["reused_<pass>"]`` is 1 or 0 for each cacheable pass of the
    method. A few entries per pass kind are kept (see docs/sweeps.md).
    ``pass_cache=False`` runs every pass of every render from scratch: use it
    to time repeated renders.
    """

    def __init__(self, timing: str = "auto", pass_cache: bool = True) -> None:
        self._core = _core.Renderer(timing, bool(pass_cache))

    @property
    def pass_cache(self) -> bool:
        """Whether renders reuse cached pass outputs."""
        return self._core.pass_cache

    def pass_cache_entries(self) -> dict[str, int]:
        """Entries the pass cache holds, per pass kind."""
        return self._core.pass_cache_entries()

    def clear_pass_cache(self) -> None:
        """Drops every cached pass output (and the GPU memory it holds)."""
        self._core.clear_pass_cache()

    @property
    def adapter_info(self) -> dict[str, Any]:
        return self._core.adapter_info()

    @property
    def timing_source(self) -> str:
        return self._core.timing_source

    def render(
        self,
        scene: Scene,
        method: str = "hard",
        *,
        camera: Camera | None = None,
        intermediates: bool = False,
        **params: Any,
    ) -> RenderResult:
        """Renders ``scene`` with ``method`` and its parameters (keyword
        arguments, named as in the papers; see SPEC section 4).

        ``camera`` overrides the scene's own. ``intermediates=True`` also
        returns the method's intermediate images (e.g. ``shadow_map``)."""
        if not isinstance(scene, Scene):
            raise SceneError(f"expected a penumbra.Scene, got {type(scene).__name__}")
        scene.check()
        if not isinstance(method, str):
            raise ParameterError(f"method must be a string, got {method!r}")
        camera = camera or scene.camera
        if camera is None:
            raise CameraError("the scene has no camera; pass camera=penumbra.Camera(...)")
        if not isinstance(camera, Camera):
            raise CameraError(f"camera must be a penumbra.Camera, got {type(camera).__name__}")
        out = self._core.render(
            [m._core_args(i) for i, m in enumerate(scene.meshes)],
            scene.light._core_args(),
            camera._core_args(),
            np.asarray(scene.ambient, dtype=np.float32),
            method,
            params,
            bool(intermediates),
        )
        return RenderResult(**out)

"""The renderer service and its results."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from collections.abc import Iterable
from typing import Any, overload

import numpy as np

from penumbra import _core
from penumbra.errors import CameraError, ParameterError, PenumbraIOError, SceneError
from penumbra.scene import Camera, Scene

__all__ = ["Renderer", "RenderResult", "adapter_info", "write_image", "methods", "method_info", "MethodInfo", "Param", "IMAGES"]

#: The images every render returns, whatever the method (intermediates add more).
IMAGES = ("radiance", "visibility", "depth", "normal", "position", "object_id")


def adapter_info() -> dict[str, Any]:
    """The GPU adapter a renderer would use: name, backend, device type,
    driver, whether it has timestamp queries, whether it has ray queries
    (``ray_queries``: method ``raytraced`` needs them; false also when
    ``PENUMBRA_DISABLE_RAY_QUERY`` is set) and whether it is software.

    Raises :class:`~penumbra.errors.GpuUnavailableError` when there is none."""
    return _core.adapter_info()


def methods(implemented_only: bool = True) -> list[str]:
    """Method names of SPEC section 4 (only those implemented, by default)."""
    return [name for name, done in _core.methods() if done or not implemented_only]


@dataclass(frozen=True)
class Param:
    """One parameter of a method, as the method declares it in the core: its
    name, ``type`` (``"bool"``, ``"int"``, ``"float"`` or ``"choice"``),
    default, accepted values (``minimum``/``maximum`` or ``choices``) and
    a line of documentation. An ``"int"`` with ``choices`` (``("auto",)``:
    ``map_size``) also takes those names."""

    name: str
    type: str
    default: Any
    doc: str
    range: str
    minimum: float | None = None
    maximum: float | None = None
    minimum_exclusive: bool = False
    choices: tuple[str, ...] | None = None


@dataclass(frozen=True)
class MethodInfo:
    """An implemented method: its name, the paper it implements and its parameters."""

    name: str
    paper: str
    params: tuple[Param, ...]

    def param(self, name: str) -> Param:
        for p in self.params:
            if p.name == name:
                return p
        raise ParameterError(f"method {self.name!r} has no parameter {name!r}; it takes {[p.name for p in self.params]}")

    def defaults(self) -> dict[str, Any]:
        """Every parameter's default, by name."""
        return {p.name: p.default for p in self.params}


def _method_infos() -> dict[str, MethodInfo]:
    out = {}
    for m in _core.method_specs():
        params = tuple(
            Param(**{**p, "choices": tuple(p["choices"]) if "choices" in p else None}) for p in m["params"]
        )
        out[m["name"]] = MethodInfo(name=m["name"], paper=m["paper"], params=params)
    return out


def method_info(method: str | None = None) -> Any:
    """The declaration of ``method`` (a :class:`MethodInfo`), or of every
    implemented method as a dict by name when ``method`` is None. This is
    what the core checks parameters against: names, types, ranges, defaults."""
    infos = _method_infos()
    if method is None:
        return infos
    if method not in infos:
        raise ParameterError(f"unknown or unimplemented method {method!r}; available: {sorted(infos)}")
    return infos[method]


def _check_wide_integers(method: str, params: dict[str, Any]) -> None:
    """An integer beyond int64 cannot reach the core (its parameters are
    64-bit): refused here with the declared range, as the core words it,
    rather than converted to a float or described as one."""
    for name, value in params.items():
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
            continue
        if -(2**63) <= int(value) < 2**63:
            continue
        try:
            accepted = method_info(method).param(name).range
        except ParameterError:
            continue  # an unknown method or parameter: the core names it
        raise ParameterError(f"parameter '{name}' of method '{method}' must be {accepted}, got int {int(value)}")


def parameter_table(method: str) -> str:
    """A Markdown table of ``method``'s parameters (name, default, accepted values, meaning)."""
    rows = ["| parameter | default | values | meaning |", "|---|---|---|---|"]
    for p in method_info(method).params:
        default = repr(p.default) if p.type == "choice" else str(p.default).lower() if p.type == "bool" else str(p.default)
        values = p.range.replace("|", "\\|")
        rows.append(f"| `{p.name}` | `{default}` | {values} | {p.doc} |")
    return "\n".join(rows)


#: The image files :func:`write_image` writes, by extension.
IMAGE_EXTENSIONS = {".png": "sRGB 8-bit", ".exr": "linear float", ".npy": "the array as is"}


def image_extension(path: str) -> str:
    """``path``'s extension, lower-cased, when :func:`write_image` writes it;
    else a :class:`~penumbra.errors.ParameterError` naming every accepted one."""
    extension = os.path.splitext(path)[1].lower()
    if extension not in IMAGE_EXTENSIONS:
        formats = ", ".join(f"{e} ({what})" for e, what in IMAGE_EXTENSIONS.items())
        raise ParameterError(f"cannot write {path}: the extension must be one of {formats}; got {extension or 'none'}")
    return extension


def write_image(path: str | bytes | os.PathLike[str] | os.PathLike[bytes], image: np.ndarray) -> None:
    """Writes a linear float image (H, W) or (H, W, 3) by extension: ``.png``
    sRGB-encoded 8-bit, ``.exr`` linear float, ``.npy`` the array as is.

    Raises :class:`~penumbra.errors.ParameterError` for a path that is not a
    path, a non-numeric image, a wrong shape or extension, and NaN or
    infinity in a PNG or EXR; :class:`~penumbra.errors.PenumbraIOError` when
    the file cannot be written."""
    try:
        path = os.fsdecode(path)
    except TypeError:
        raise ParameterError(f"path must be a str or os.PathLike, got {type(path).__name__}") from None
    try:
        array = np.asarray(image)
    except (TypeError, ValueError) as e:
        raise ParameterError(f"image must be a numeric array: {e}") from None
    if array.dtype.kind not in "biuf":
        raise ParameterError(f"image must be a numeric array, got dtype {array.dtype}")
    if image_extension(path) == ".npy":
        try:
            np.save(path, array)
        except OSError as e:
            raise PenumbraIOError(f"writing {path}: {e.strerror or e}") from None
        return
    with np.errstate(over="ignore"):
        # Beyond float32's range becomes inf, which the core then refuses.
        data = np.ascontiguousarray(array, dtype=np.float32)
    _core.write_image(path, data)


class _Image:
    """A read-only attribute of :class:`RenderResult` that is one of its
    images, by the attribute's name (``result.visibility`` is
    ``result["visibility"]``), documented by ``doc``."""

    def __init__(self, doc: str) -> None:
        self.__doc__ = doc

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    @overload
    def __get__(self, result: None, owner: type) -> _Image: ...
    @overload
    def __get__(self, result: RenderResult, owner: type | None = None) -> np.ndarray: ...
    def __get__(self, result: RenderResult | None, owner: type | None = None) -> np.ndarray | _Image:
        # On the class (help(), the docs): the attribute itself, with its doc.
        return self if result is None else result._image(self.name)


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

    def _image(self, name: str) -> np.ndarray:
        if name not in self.images:
            raise ParameterError(f"this result has no image {name!r}: it read back {sorted(self.images)} (see Renderer.render's outputs=)")
        return self.images[name]

    radiance = _Image("Linear radiance, float32 (H, W, 3).")
    visibility = _Image("Visible fraction of the light in [0, 1], float32 (H, W); 0 on background.")
    depth = _Image("Distance along the camera axis, float32 (H, W); 0 on background.")
    normal = _Image("Unit shading normal, float32 (H, W, 3); 0 on background.")
    position = _Image("World position, float32 (H, W, 3); 0 on background.")
    object_id = _Image("Object id, int32 (H, W); -1 on background.")

    @property
    def reused_passes(self) -> list[str]:
        """Passes whose cached outputs this render reused (they have no
        entry in ``timings``); empty without a pass cache. (The geometry kept
        from an earlier render, ``stats["reused_geometry"]``, is not a pass.)"""
        prefix = "reused_"
        return [k[len(prefix):] for k, v in self.stats.items() if k.startswith(prefix) and k not in ("reused_passes", "reused_geometry") and v]

    def __getitem__(self, name: str) -> np.ndarray:
        return self._image(name)

    def save(self, path: str | os.PathLike[str], image: str = "radiance") -> None:
        """Writes one image (radiance by default) with :func:`write_image`."""
        if image not in self.images:
            raise ParameterError(f"no image named {image!r}; this result has {sorted(self.images)}")
        write_image(path, self.images[image])


def _outputs(outputs: Iterable[str] | None) -> list[str] | None:
    """The output names as a list for the core, checked here for type (the
    core checks the names)."""
    if outputs is None:
        return None
    if isinstance(outputs, (str, bytes)) or not isinstance(outputs, Iterable):
        raise ParameterError(f"outputs must be a list of image names of {list(IMAGES)}, got {outputs!r}")
    names = list(outputs)
    if not all(isinstance(n, str) for n in names):
        raise ParameterError(f"outputs must be a list of image names of {list(IMAGES)}, got {names!r}")
    return names


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

    Either way, the renderer keeps the last scene geometry it rendered,
    prepared and uploaded, with its casters for the last few lights, and a
    render whose meshes are the same bit for bit (vertices, faces, normals,
    materials, transforms, names) starts from them
    (``stats["reused_geometry"]`` is 1): no per-render preparation or upload
    of unchanged geometry. :meth:`clear_pool` forgets it.
    """

    def __init__(self, timing: str = "auto", pass_cache: bool = True) -> None:
        if not isinstance(timing, str):
            raise ParameterError(f"timing must be 'auto' or 'cpu', got {timing!r}")
        # The core parses the mode and refuses a pass_cache that is not a bool.
        self._core = _core.Renderer(timing, pass_cache)

    @property
    def pass_cache(self) -> bool:
        """Whether renders reuse cached pass outputs."""
        return self._core.pass_cache

    def pass_cache_entries(self) -> dict[str, int]:
        """Entries the pass cache holds, per pass kind."""
        return self._core.pass_cache_entries()

    def pool_stats(self) -> dict[str, int]:
        """What the renderer's pool of GPU resources (textures, buffers and
        bind groups reused across renders) holds: counts, and bytes in use
        (by a render, the pass cache, or the geometry kept from the last
        render: its vertex and index buffers, with or without a pass cache)
        and free."""
        return self._core.pool_stats()

    def clear_pool(self) -> None:
        """Releases every pooled GPU resource not in use (free ones beyond
        256 MiB are released after each render anyway), and the kept
        geometry's buffers: the next render prepares its scene afresh."""
        self._core.clear_pool()

    def clear_pass_cache(self) -> None:
        """Drops every cached pass output and the kept geometry, and releases
        the pooled GPU memory that no render holds."""
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
        outputs: Iterable[str] | None = None,
        **params: Any,
    ) -> RenderResult:
        """Renders ``scene`` with ``method`` and its parameters (keyword
        arguments, named as in the papers; see SPEC section 4, and
        :func:`method_info` or docs/parameters.md for each method's).

        ``camera`` overrides the scene's own. ``intermediates=True`` also
        returns the method's intermediate images (e.g. ``shadow_map``).
        ``outputs`` names the images to read back, of ``IMAGES``
        (``radiance``, ``visibility``, ``depth``, ``position``, ``normal``,
        ``object_id``; all by default): a render that needs visibility alone
        reads back visibility alone, and skips shading unless ``radiance``
        is asked for. ``stats["geometry_pixels"]`` is there when ``normal``
        or ``object_id`` is."""
        if not isinstance(scene, Scene):
            raise SceneError(f"expected a penumbra.Scene, got {type(scene).__name__}")
        core_scene = scene._core_value()
        if not isinstance(method, str):
            raise ParameterError(f"method must be a string, got {method!r}")
        camera = camera or scene.camera
        if camera is None:
            raise CameraError("the scene has no camera; pass camera=penumbra.Camera(...)")
        if not isinstance(camera, Camera):
            raise CameraError(f"camera must be a penumbra.Camera, got {type(camera).__name__}")
        _check_wide_integers(method, params)
        wanted = _outputs(outputs)
        # intermediates goes as is: the core refuses anything but a bool.
        out = self._core.render(core_scene, camera._core_value(), method, params, intermediates, wanted)
        return RenderResult(**out)

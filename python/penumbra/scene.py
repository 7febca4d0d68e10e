"""The scene model of SPEC section 3: meshes, a sphere light, a camera.

These classes turn what the caller hands in (lists, numpy arrays of any
dtype, trimesh meshes) into the exact arrays the core takes, raising a typed
error naming the problem when that is impossible. The core validates the
content (finiteness, index ranges, degenerate geometry) before anything
reaches the GPU.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, NamedTuple, Sequence

import numpy as np
import numpy.typing as npt

from penumbra.errors import CameraError, LightError, MeshError, SceneError

if TYPE_CHECKING:
    import trimesh

__all__ = ["Mesh", "SphereLight", "Camera", "Scene", "WorldGeometry", "world_geometry"]

ArrayLike = npt.ArrayLike

#: Object ids are int32 in the object-id image, where -1 marks the background.
MAX_OBJECT_ID = 2**31 - 1


def _float_array(value: ArrayLike, shape: tuple[int | None, ...], what: str, error: type[Exception]) -> np.ndarray:
    """`value` as a C-contiguous float32 array of `shape` (None: any length)."""
    try:
        array = np.asarray(value)
    except (TypeError, ValueError) as e:
        raise error(f"{what} must be numeric: {e}") from None
    if array.dtype == object or not (np.issubdtype(array.dtype, np.number) or array.dtype == np.bool_):
        raise error(f"{what} must be numeric, got dtype {array.dtype}")
    if np.issubdtype(array.dtype, np.complexfloating):
        raise error(f"{what} must be real, got dtype {array.dtype}")
    if array.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, array.shape)):
        expected = "(" + ", ".join("N" if s is None else str(s) for s in shape) + ")"
        raise error(f"{what} must have shape {expected}, got {array.shape}")
    with np.errstate(over="ignore"):
        # Values beyond float32's range become inf, which the core then names.
        return np.ascontiguousarray(array, dtype=np.float32)


def _rgb(value: ArrayLike, what: str, error: type[Exception]) -> np.ndarray:
    """A scalar (grey) or three values as a float32 RGB triple."""
    array = np.asarray(value) if not isinstance(value, (int, float)) else np.full(3, value)
    if array.ndim == 0:
        array = np.full(3, array)
    return _float_array(array, (3,), what, error)


def _real(value: Any, what: str, error: type[Exception]) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise error(f"{what} must be a real number, got {value!r}")
    return float(value)


def _size(value: Any, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise CameraError(f"{what} must be an integer, got {value!r}")
    if value < 0 or value > 2**31:
        raise CameraError(f"{what} must be at least 1 and at most 2^31, got {value}")
    return int(value)


def _name(value: Any) -> str:
    """A mesh name as text the core (UTF-8) can carry."""
    name = str(value)
    try:
        name.encode("utf-8")
    except UnicodeEncodeError as e:
        raise MeshError(f"mesh name {name!r} is not valid Unicode text ({e.reason} at position {e.start})") from None
    return name


def _object_id(value: Any, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise MeshError(f"mesh '{name}': object_id must be an integer, got {value!r}")
    if not 0 <= int(value) <= MAX_OBJECT_ID:
        raise MeshError(f"mesh '{name}': object_id must be >= 0 (-1 marks the background) and at most {MAX_OBJECT_ID} (int32), got {int(value)}")
    return int(value)


class Mesh:
    """A triangle mesh with a diffuse albedo and an object id.

    ``vertices`` (N, 3) and ``faces`` (M, 3) with counter-clockwise front
    faces; ``normals`` (N, 3) optional per-vertex shading normals (face
    normals otherwise); ``transform`` an optional affine 4x4 object-to-world
    matrix (row-major, numpy convention: ``world = T @ [x, y, z, 1]``);
    ``object_id`` a non-negative integer (default: the mesh's index in its scene).
    """

    def __init__(
        self,
        vertices: ArrayLike,
        faces: ArrayLike,
        *,
        albedo: ArrayLike = 0.8,
        object_id: int | None = None,
        transform: ArrayLike | None = None,
        normals: ArrayLike | None = None,
        name: str = "mesh",
    ) -> None:
        self.name = name = _name(name)
        self.vertices = _float_array(vertices, (None, 3), f"mesh '{name}': vertices", MeshError)
        self.faces = self._faces(faces)
        self.normals = None if normals is None else _float_array(normals, (None, 3), f"mesh '{name}': normals", MeshError)
        self.albedo = _rgb(albedo, f"mesh '{name}': albedo", MeshError)
        self.object_id = None if object_id is None else _object_id(object_id, name)
        self.transform = (
            np.eye(4, dtype=np.float32)
            if transform is None
            else _float_array(transform, (4, 4), f"mesh '{name}': transform", MeshError)
        )

    def _faces(self, faces: ArrayLike) -> np.ndarray:
        try:
            array = np.asarray(faces)
        except (TypeError, ValueError) as e:
            raise MeshError(f"mesh '{self.name}': faces must be integers: {e}") from None
        if array.size == 0:
            array = array.reshape(0, 3) if array.ndim <= 1 else array
        # By kind, not np.integer: numpy counts timedelta64 as an integer type.
        if array.dtype.kind not in "iu":
            raise MeshError(f"mesh '{self.name}': faces must be integers, got dtype {array.dtype}")
        if array.ndim != 2 or array.shape[1] != 3:
            raise MeshError(f"mesh '{self.name}': faces must have shape (M, 3), got {array.shape}")
        if array.size and array.min() < 0:
            bad = int(np.argwhere(array < 0)[0][0])
            raise MeshError(f"mesh '{self.name}': face {bad} has a negative index {array[bad].tolist()}")
        if array.size and array.max() >= 2**32:
            raise MeshError(f"mesh '{self.name}': face index {int(array.max())} exceeds uint32")
        return np.ascontiguousarray(array, dtype=np.uint32)

    @classmethod
    def from_trimesh(cls, mesh: "trimesh.Trimesh", **kwargs: Any) -> "Mesh":
        """A mesh from a ``trimesh.Trimesh`` (its vertices and faces; its vertex
        normals only if you pass ``normals=mesh.vertex_normals``)."""
        import trimesh

        if isinstance(mesh, trimesh.Scene):
            raise MeshError("got a trimesh.Scene; pass scene.to_mesh() or load with force='mesh'")
        if not isinstance(mesh, trimesh.Trimesh):
            raise MeshError(f"expected a trimesh.Trimesh, got {type(mesh).__name__}")
        kwargs.setdefault("name", mesh.metadata.get("name") or mesh.metadata.get("file_name") or "mesh")
        return cls(np.asarray(mesh.vertices), np.asarray(mesh.faces), **kwargs)

    def __repr__(self) -> str:
        return f"Mesh({self.name!r}, {len(self.vertices)} vertices, {len(self.faces)} faces)"

    def _core_value(self, index: int) -> "CoreMesh":
        # The attributes are public and may have been replaced since __init__
        # (a float64 or wrongly shaped array would otherwise reach the core as
        # an untyped TypeError): coerce and check them again. For arrays that
        # are already right this copies nothing.
        name = _name(self.name)
        return CoreMesh(
            name=name,
            vertices=_float_array(self.vertices, (None, 3), f"mesh '{name}': vertices", MeshError),
            faces=self._faces(self.faces),
            normals=None if self.normals is None else _float_array(self.normals, (None, 3), f"mesh '{name}': normals", MeshError),
            albedo=_rgb(self.albedo, f"mesh '{name}': albedo", MeshError),
            object_id=_object_id(index if self.object_id is None else self.object_id, name),
            transform=_float_array(self.transform, (4, 4), f"mesh '{name}': transform", MeshError),
        )


def _radius(value: Any) -> float:
    radius = _real(value, "light radius", LightError)
    if radius < 0 or not math.isfinite(radius):
        raise LightError(f"light radius must be finite and >= 0, got {radius}")
    return radius


class SphereLight:
    """A sphere light: ``center``, ``radius`` (>= 0) and either its surface
    ``radiance`` L (RGB or grey) or its point-equivalent ``intensity``
    I = L * pi * r^2. A radius-0 light is a point light and needs ``intensity``."""

    def __init__(
        self,
        center: ArrayLike,
        radius: float,
        radiance: ArrayLike | None = None,
        *,
        intensity: ArrayLike | None = None,
    ) -> None:
        self.center = _float_array(center, (3,), "light center", LightError)
        self.radius = _radius(radius)
        if (radiance is None) == (intensity is None):
            raise LightError("give exactly one of radiance and intensity")
        if radiance is not None:
            if self.radius == 0:
                raise LightError("a radius-0 light has no area, so radiance cannot set its power; give intensity")
            with np.errstate(over="ignore"):
                self.intensity = _rgb(radiance, "light radiance", LightError) * np.float32(math.pi * self.radius**2)
        elif intensity is not None:
            self.intensity = _rgb(intensity, "light intensity", LightError)

    @property
    def radiance(self) -> np.ndarray | None:
        """L = I / (pi r^2), or None for a point light."""
        if self.radius == 0:
            return None
        return (self.intensity / np.float32(math.pi * self.radius**2)).astype(np.float32)

    def with_radius(self, radius: float) -> "SphereLight":
        """The same light position and intensity (so the same unshadowed
        irradiance) with another radius."""
        return SphereLight(self.center, radius, intensity=self.intensity)

    def __repr__(self) -> str:
        return f"SphereLight(center={self.center.tolist()}, radius={self.radius}, intensity={self.intensity.tolist()})"

    def _core_value(self) -> "CoreLight":
        # Checked again, as a mesh's attributes are: they are public.
        return CoreLight(
            center=_float_array(self.center, (3,), "light center", LightError),
            radius=np.float32(_radius(self.radius)).item(),
            intensity=_rgb(self.intensity, "light intensity", LightError),
        )


@dataclass(frozen=True)
class Camera:
    """A pinhole camera: ``look_at(eye, target, up)``, vertical field of view
    ``fov_y`` in degrees, image ``width`` x ``height``. Row 0 is the top."""

    eye: Sequence[float]
    target: Sequence[float]
    up: Sequence[float] = (0.0, 1.0, 0.0)
    fov_y: float = 45.0
    width: int = 512
    height: int = 512

    def __post_init__(self) -> None:
        for what in ("eye", "target", "up"):
            array = _float_array(getattr(self, what), (3,), f"camera {what}", CameraError)
            if not np.isfinite(array).all():
                raise CameraError(f"camera: {what} must be finite, got {array.tolist()}")
            object.__setattr__(self, what, tuple(float(x) for x in array))
        object.__setattr__(self, "fov_y", _real(self.fov_y, "camera fov_y", CameraError))
        object.__setattr__(self, "width", _size(self.width, "camera width"))
        object.__setattr__(self, "height", _size(self.height, "camera height"))
        if self.width < 1 or self.height < 1:
            # Here, not at render time: Camera.with_size(0, 0) is already wrong.
            raise CameraError(f"camera: image size must be at least 1x1, got {self.width}x{self.height}")

    @classmethod
    def look_at(cls, eye: Sequence[float], target: Sequence[float], up: Sequence[float] = (0.0, 1.0, 0.0), **kwargs: Any) -> "Camera":
        return cls(eye, target, up, **kwargs)

    def with_size(self, width: int, height: int) -> "Camera":
        return replace(self, width=width, height=height)

    def _core_value(self) -> "CoreCamera":
        f = lambda v: np.asarray(v, dtype=np.float32)  # noqa: E731
        return CoreCamera(f(self.eye), f(self.target), f(self.up), np.float32(self.fov_y).item(), self.width, self.height)


@dataclass
class Scene:
    """Meshes lit by one sphere light, with an optional default camera and an
    ambient term (``radiance += albedo * ambient``; 0 by default)."""

    meshes: list[Mesh]
    light: SphereLight
    camera: Camera | None = None
    ambient: ArrayLike = 0.0
    name: str = "scene"
    metadata: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.check()

    def check(self) -> None:
        """Checks the parts' types (again: the fields are public and may be
        replaced after construction; the renderer calls this before each render)."""
        if isinstance(self.meshes, Mesh):
            self.meshes = [self.meshes]
        if isinstance(self.meshes, (str, bytes)) or not isinstance(self.meshes, (list, tuple)):
            raise SceneError(f"meshes must be a list of penumbra.Mesh, got {type(self.meshes).__name__}")
        self.meshes = list(self.meshes)
        for i, m in enumerate(self.meshes):
            if not isinstance(m, Mesh):
                raise SceneError(f"meshes[{i}] is a {type(m).__name__}, not a penumbra.Mesh (use Mesh.from_trimesh)")
        if not isinstance(self.light, SphereLight):
            raise SceneError(f"light must be a penumbra.SphereLight, got {type(self.light).__name__}")
        if self.camera is not None and not isinstance(self.camera, Camera):
            raise SceneError(f"camera must be a penumbra.Camera, got {type(self.camera).__name__}")
        self.ambient = _rgb(self.ambient, "ambient", SceneError)

    def with_light(self, light: SphereLight) -> "Scene":
        return replace(self, light=light)

    def with_camera(self, camera: Camera) -> "Scene":
        return replace(self, camera=camera)

    def _core_value(self) -> "CoreScene":
        self.check()
        return CoreScene(
            meshes=[m._core_value(i) for i, m in enumerate(self.meshes)],
            light=self.light._core_value(),
            ambient=np.asarray(self.ambient, dtype=np.float32),
        )


# What crosses the binding: rust/penumbra-py reads these attributes by name
# (its `CoreScene`, `CoreMesh`, `CoreLight` and `CoreCamera`), so no argument
# order is written twice. The classes above build them, checked and coerced
# to the exact dtypes, just before each render.


@dataclass(frozen=True)
class CoreMesh:
    name: str
    vertices: np.ndarray  # float32 (N, 3)
    faces: np.ndarray  # uint32 (M, 3)
    normals: np.ndarray | None  # float32 (N, 3)
    albedo: np.ndarray  # float32 (3,)
    object_id: int
    transform: np.ndarray  # float32 (4, 4), row-major


@dataclass(frozen=True)
class CoreLight:
    center: np.ndarray  # float32 (3,)
    radius: float
    intensity: np.ndarray  # float32 (3,)


@dataclass(frozen=True)
class CoreCamera:
    eye: np.ndarray  # float32 (3,)
    target: np.ndarray
    up: np.ndarray
    fov_y: float
    width: int
    height: int


@dataclass(frozen=True)
class CoreScene:
    meshes: list[CoreMesh]
    light: CoreLight
    ambient: np.ndarray  # float32 (3,)


class WorldGeometry(NamedTuple):
    """A mesh in world space: float64 ``vertices`` (N, 3), int64 ``faces``
    (M, 3) counter-clockwise from the front, and unit ``normals`` (N, 3) or None."""

    vertices: np.ndarray
    faces: np.ndarray
    normals: np.ndarray | None


def world_geometry(mesh: Mesh) -> WorldGeometry:
    """``mesh`` in world space, as the core builds it (``Scene::prepare`` in
    rust/penumbra-core/src/scene.rs): vertices through the transform, vertex
    normals through its inverse transpose, and, where the transform mirrors
    (negative determinant), faces with their winding reversed so that their
    front side is the one the transform carries along. The one copy of this
    in Python: the Mitsuba export, the ray caster and the transition
    measurements use it."""
    t = np.asarray(mesh.transform, dtype=np.float64)
    linear = t[:3, :3]
    vertices = np.asarray(mesh.vertices, dtype=np.float64) @ linear.T + t[:3, 3]
    faces = np.asarray(mesh.faces, dtype=np.int64)
    if np.linalg.det(linear) < 0:
        faces = faces[:, [0, 2, 1]]
    normals = None
    if mesh.normals is not None:
        n = np.asarray(mesh.normals, dtype=np.float64) @ np.linalg.inv(linear)
        normals = n / np.linalg.norm(n, axis=1, keepdims=True)
    return WorldGeometry(vertices, faces, normals)

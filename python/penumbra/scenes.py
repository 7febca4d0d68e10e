"""Built-in scenes, generated in code: ``names()`` lists them, ``get(name)``
builds one with its camera and light.

Each is a caster (or several) over a 10 x 10 ground slab whose top is at
y = 0 (closed, so the silhouette methods accept it), lit by a sphere light
above, seen by a camera from the front and above:

- ``sphere_on_plane``: a smooth sphere floating over the plane (the default scene).
- ``cube_on_plane``: a rotated cube floating over the plane.
- ``overlapping_casters``: a sphere high up and a box lower down whose shadows
  overlap in light space (PVM's overlap artifact, Cournia 4.3).
- ``resting_box``: a tall box standing on the plane: the penumbra shrinks to
  zero width where it touches (contact hardening).
"""

from __future__ import annotations

import functools
import math
import os
import warnings
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable

import numpy as np
import trimesh

from penumbra.errors import MeshError, ParameterError
from penumbra.scene import Camera, Mesh, Scene, SphereLight

__all__ = [
    "names",
    "get",
    "DEFAULT",
    "ground_plane",
    "ground_slab",
    "sphere",
    "box",
    "from_mesh",
    "SETUPS",
    "CLOSED_MESHES",
    "SUITE_SETUPS",
    "real_mesh_suite",
    "load_mesh",
    "wide_floor",
    "cornell_box",
    "sponza",
    "inverted_box",
    "meshes_folder",
    "GENERATOR_MESHES",
    "GeneratedSpec",
    "generate",
    "generated_spec",
    "generated_suite",
    "GENERATED_PREFIX",
    "REAL_FORMS",
    "real_names",
    "expand_names",
    "lit_plane",
    "sphere_over_plane",
    "SPHERE_OCCLUDER",
]

DEFAULT = "sphere_on_plane"
_WIDTH, _HEIGHT = 512, 512


def ground_plane(half_size: float = 5.0, albedo: float = 0.8, object_id: int = 0) -> Mesh:
    """A square at y = 0 facing up (+y), made of two triangles."""
    h = half_size
    vertices = np.array([[-h, 0, -h], [h, 0, -h], [h, 0, h], [-h, 0, h]], dtype=np.float32)
    faces = np.array([[0, 2, 1], [0, 3, 2]], dtype=np.uint32)
    return Mesh(vertices, faces, albedo=albedo, object_id=object_id, name="ground")


def ground_slab(half_size: float = 5.0, thickness: float = 0.2, albedo: float = 0.8, object_id: int = 0) -> Mesh:
    """A closed box whose top face is the square at y = 0 (a ground that
    PVM and the other silhouette methods accept: they need closed casters)."""
    m = trimesh.creation.box(extents=(2 * half_size, thickness, 2 * half_size))
    vertices = np.asarray(m.vertices) - (0.0, thickness / 2, 0.0)
    return Mesh(vertices, m.faces, albedo=albedo, object_id=object_id, name="ground")


def sphere(
    center: tuple[float, float, float],
    radius: float,
    *,
    subdivisions: int = 4,
    smooth: bool = False,
    albedo: float = 0.7,
    object_id: int = 1,
    name: str = "sphere",
) -> Mesh:
    """An icosphere (counter-clockwise outward faces). ``smooth=True`` gives
    it the true sphere's normals at its vertices (the radial directions),
    which Penumbra and the Mitsuba export both interpolate across each face;
    the geometry, and so every shadow, stays the icosphere's."""
    m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    vertices = np.asarray(m.vertices, dtype=np.float64)
    normals = vertices / np.linalg.norm(vertices, axis=1, keepdims=True) if smooth else None
    return Mesh(vertices + np.asarray(center), m.faces, albedo=albedo, object_id=object_id, normals=normals, name=name)


def box(center: tuple[float, float, float], extents: tuple[float, float, float], *, yaw_degrees: float = 0.0, albedo: float = 0.7, object_id: int = 1, name: str = "box") -> Mesh:
    """An axis-aligned box of full ``extents``, turned by ``yaw_degrees`` about y."""
    m = trimesh.creation.box(extents=extents)
    transform = trimesh.transformations.rotation_matrix(math.radians(yaw_degrees), [0, 1, 0])
    transform[:3, 3] = center
    return Mesh(m.vertices, m.faces, albedo=albedo, object_id=object_id, transform=transform, name=name)


def lit_plane() -> Scene:
    """A coloured ground plane under a sphere light, nothing casting a shadow:
    Mitsuba's radiance and Penumbra's agree there where both are exact (the
    export checks of docs/ground_truth.md and tests/test_ground_truth.py)."""
    light = SphereLight((0.7, 3.0, -0.4), 0.5, radiance=(40.0, 25.0, 10.0))
    camera = Camera(eye=(1.0, 4.0, 6.0), target=(0.0, 0.0, -0.5), fov_y=50, width=80, height=60)
    plane = ground_plane()
    return Scene([Mesh(plane.vertices, plane.faces, albedo=(0.8, 0.6, 0.4))], light, camera)


#: The occluder of `sphere_over_plane`: its centre and radius.
SPHERE_OCCLUDER = ((0.2, 1.5, 0.0), 0.8)


def sphere_over_plane() -> Scene:
    """One sphere occluder (`SPHERE_OCCLUDER`) over the ground plane, whose
    shadow has a closed form (`analytic.sphere_occluder_visibility`): the
    check of the ground truth's visibility estimator (docs/ground_truth.md)."""
    center, radius = SPHERE_OCCLUDER
    light = SphereLight((0.0, 4.5, 0.3), 0.7, intensity=30.0)
    camera = Camera(eye=(0.0, 6.0, 4.0), target=(0.0, 0.0, 0.0), fov_y=50, width=96, height=96)
    return Scene([ground_plane(), sphere(center, radius, subdivisions=6)], light, camera)


def _camera() -> Camera:
    return Camera(eye=(0.0, 5.0, 9.0), target=(0.0, 0.8, 0.0), fov_y=40.0, width=_WIDTH, height=_HEIGHT)


def _light(radius: float) -> SphereLight:
    # Intensity gives a lit-plane radiance of about 0.5 under the light.
    return SphereLight(center=(1.5, 6.0, 1.0), radius=radius, intensity=80.0)


def _sphere_on_plane() -> Scene:
    # Smooth: vertex normals on five subdivisions (20480 faces). Flat faces
    # look faceted and, smaller than a pixel, shade each pixel by the one face
    # its centre hits where Mitsuba averages the pixel (0.85-1.2% radiance
    # RMSE on the sphere); vertex normals on four subdivisions make shadow-map
    # tests leak light at the terminator, where the normals are 1.5-2.9
    # degrees off the faces (`reference` twice as far from the ground truth).
    # Five subdivisions with vertex normals match Mitsuba to 0.1% in radiance
    # and as flat faces do in visibility: benchmarks/sphere_tessellation.py.
    ball = sphere((0.0, 1.6, 0.0), 1.0, subdivisions=5, smooth=True)
    return Scene([ground_slab(), ball], _light(0.5), _camera(), name="sphere_on_plane")


def _cube_on_plane() -> Scene:
    return Scene([ground_slab(), box((0.0, 1.6, 0.0), (1.5, 1.5, 1.5), yaw_degrees=30.0)], _light(0.5), _camera(), name="cube_on_plane")


def _overlapping_casters() -> Scene:
    casters = [
        sphere((0.6, 3.2, 0.4), 0.6, object_id=1, name="high_sphere"),
        box((-0.4, 1.2, -0.2), (1.4, 0.4, 1.4), yaw_degrees=15.0, object_id=2, name="low_box"),
    ]
    return Scene([ground_slab(), *casters], _light(0.5), _camera(), name="overlapping_casters")


def _resting_box() -> Scene:
    return Scene([ground_slab(), box((0.0, 1.0, 0.0), (0.8, 2.0, 0.8), yaw_degrees=20.0)], _light(0.8), _camera(), name="resting_box")


_SCENES: dict[str, Callable[[], Scene]] = {
    "sphere_on_plane": _sphere_on_plane,
    "cube_on_plane": _cube_on_plane,
    "overlapping_casters": _overlapping_casters,
    "resting_box": _resting_box,
}


def names() -> list[str]:
    """Names of the built-in scenes, the default first."""
    return list(_SCENES)


def get(name: str = DEFAULT, *, width: int | None = None, height: int | None = None, light_radius: float | None = None) -> Scene:
    """Builds the scene ``name``, optionally at another image size or light
    radius: a built-in scene (:func:`names`), or one from the shared meshes
    (:func:`meshes_folder`; :func:`real_names` lists the forms):
    ``"generated:<seed>"`` (:func:`generate`), ``"mesh:<file>"``
    (:func:`from_mesh`, ``setup="close"``), ``"wide_floor:<file>"``
    (:func:`wide_floor`), ``"cornell_box"`` and ``"sponza"``; and
    ``"wide_floor"``, :func:`wide_floor` with its box caster, and
    ``"acute_caster"``, :func:`acute_caster` (no mesh file)."""
    if not isinstance(name, str):
        raise ParameterError(f"unknown scene {name!r}: a scene name is a string; built-in scenes: {names()}")
    if name in _SCENES:
        scene = _SCENES[name]()
    elif name == "acute_caster":
        scene = acute_caster()
    elif name == "wide_floor":
        scene = wide_floor(width=_WIDTH if width is None else width, height=height if height is not None else (_HEIGHT if width is None else width))
    else:
        scene = _real_scene(name, _WIDTH if width is None else width, height if height is not None else (_HEIGHT if width is None else width))
    assert scene.camera is not None
    if width is not None or height is not None:
        scene = scene.with_camera(
            scene.camera.with_size(
                scene.camera.width if width is None else width,
                scene.camera.height if height is None else height,
            )
        )
    if light_radius is not None:
        scene = scene.with_light(scene.light.with_radius(light_radius))
    return scene


#: The forms of scene names that read the shared meshes (see :func:`get`).
REAL_FORMS = ("generated:<seed>", "generated:<first>..<last>", "mesh:<file>", "wide_floor:<file>", "cornell_box", "sponza")


def real_names() -> list[str]:
    """The forms of :func:`get`'s names of scenes from the shared meshes."""
    return list(REAL_FORMS)


def _parse(name: str) -> tuple[str, str]:
    """(kind, argument) of a scene name that is not built in; a
    :class:`ParameterError` naming the forms for anything else."""
    kind, _, arg = name.partition(":")
    if name in ("cornell_box", "sponza", "wide_floor", "acute_caster"):
        return name, ""
    if kind == "generated" and arg.isdigit():
        return kind, arg
    if kind == "generated":
        raise ParameterError(f"a generated scene is named {GENERATED_PREFIX}<seed> with a seed of digits, got {name!r}")
    if kind in ("mesh", "wide_floor") and arg:
        return kind, arg
    raise ParameterError(f"unknown scene {name!r}; built-in scenes: {names()}; from the shared meshes: {list(REAL_FORMS)}")


def expand_names(entries: list[str]) -> list[str]:
    """Scene names with every ``"generated:<first>..<last>"`` range written
    out (both ends included); each name checked (not built)."""
    out: list[str] = []
    for entry in entries:
        if isinstance(entry, str) and entry.startswith(GENERATED_PREFIX) and ".." in entry:
            first, _, last = entry[len(GENERATED_PREFIX):].partition("..")
            if not (first.isdigit() and last.isdigit() and int(first) <= int(last)):
                raise ParameterError(f"a range of generated scenes is {GENERATED_PREFIX}<first>..<last> with first <= last, got {entry!r}")
            out += [f"{GENERATED_PREFIX}{k}" for k in range(int(first), int(last) + 1)]
            continue
        if not isinstance(entry, str):
            raise ParameterError(f"unknown scene {entry!r}: a scene name is a string")
        if entry not in _SCENES:
            _parse(entry)
        out.append(entry)
    return out


def _real_scene(name: str, width: int, height: int) -> Scene:
    kind, arg = _parse(name)
    root = meshes_folder()
    if root is None:
        raise ParameterError(f"scene {name!r} needs the shared meshes: set PENUMBRA_MESHES (../shared/meshes beside the repository was not found)")
    if kind == "generated":
        return generate(int(arg), width=width, height=height, folder=root)
    if kind == "cornell_box":
        return cornell_box(str(root / "CornellBox-Original.obj"), width=width, height=height)
    if kind == "sponza":
        return sponza(str(root / "sponza.obj"), width=width, height=height)
    path = root / arg
    if not path.is_file():
        raise ParameterError(f"scene {name!r}: no mesh file {str(path)!r}")
    scene = from_mesh(str(path), width=width, height=height, setup="close") if kind == "mesh" else wide_floor(str(path), width=width, height=height)
    return replace(scene, name=name)


def _obj_with_relative_indices(path: str) -> trimesh.Trimesh | None:
    """An OBJ file whose faces use relative (negative) indices, read by
    positions only; None for any other file.

    trimesh 5.2 resolves relative indices wrongly when an OBJ has several
    groups (mikedh/trimesh#2364; the Cornell box of ../shared/meshes loses
    most of its walls), and silently, so such files are read here: each
    negative index counts back from the vertices read so far (the OBJ
    specification), and polygons are fan-triangulated."""
    if not str(path).lower().endswith(".obj"):
        return None
    with open(path, encoding="utf-8", errors="replace") as f:
        lines = f.read().splitlines()
    if not any(line.startswith("f ") and " -" in line for line in lines):
        return None
    vertices: list[list[float]] = []
    faces: list[list[int]] = []
    for number, line in enumerate(lines, 1):
        fields = line.split()
        if not fields:
            continue
        if fields[0] == "v":
            vertices.append([float(x) for x in fields[1:4]])
        elif fields[0] == "f":
            corners = []
            for field in fields[1:]:
                i = int(field.split("/")[0])
                i = i - 1 if i > 0 else len(vertices) + i
                if not 0 <= i < len(vertices):
                    raise ValueError(f"line {number}: vertex index {field} out of range")
                corners.append(i)
            faces.extend([corners[0], corners[k], corners[k + 1]] for k in range(1, len(corners) - 1))
    return trimesh.Trimesh(np.array(vertices, dtype=np.float64).reshape(-1, 3), np.array(faces, dtype=np.int64).reshape(-1, 3), process=False)


def load_mesh(path: str) -> trimesh.Trimesh:
    """The triangles of a mesh file (anything trimesh reads; OBJ files with
    relative indices read here), as they are in the file."""
    # trimesh merges vertices by casting their coordinates to integers: a
    # coordinate beyond float32's range warns there ("invalid value in cast")
    # and may collapse the mesh. The coordinates are checked, and named,
    # before that warning reaches the caller.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            loaded = _obj_with_relative_indices(path) or trimesh.load(path, force="mesh")
        except Exception as e:  # trimesh raises many types for unreadable files
            raise MeshError(f"cannot read mesh file {path!r}: {e}") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise MeshError(f"mesh file {path!r} holds no triangles")
    raw = np.asarray(loaded.vertices, dtype=np.float64)
    limit = float(np.finfo(np.float32).max)
    bad = ~(np.abs(raw) <= limit).all(axis=1)
    if bad.any():
        i = int(np.argmax(bad))
        raise MeshError(f"mesh file {path!r}: vertex {i} {raw[i].tolist()} has a coordinate that is NaN, infinite or beyond float32's range (+-{limit:.4g})")
    for w in caught:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno, source=w.source)
    extent = float(np.max(loaded.extents))
    if not math.isfinite(extent) or extent <= 0:
        raise MeshError(f"mesh file {path!r} has a degenerate or non-finite bounding box")
    return loaded


def _resting(path: str, size: float) -> Mesh:
    """The mesh of `path` scaled to a `size`-unit bounding box, centred on
    the y axis and resting on y = 0."""
    loaded = load_mesh(path)
    vertices = (np.asarray(loaded.vertices) - loaded.bounds.mean(axis=0)) * (size / float(np.max(loaded.extents)))
    vertices[:, 1] -= vertices[:, 1].min() - 1e-3
    return Mesh(vertices, np.asarray(loaded.faces), albedo=0.7, object_id=1, name=str(path).rsplit("/", 1)[-1])


# The ways from_mesh places a mesh, its light and camera (see from_mesh).
SETUPS = ("default", "close", "wide_floor")


def from_mesh(path: str, *, width: int = _WIDTH, height: int = _HEIGHT, light_radius: float = 0.5, setup: str = "default") -> Scene:
    """A scene around a mesh file (anything trimesh reads), resting on a
    closed ground slab; ``setup`` says how:

    - ``"default"``: the mesh scaled to a 2.5-unit bounding box on the
      10 x 10 ground slab, with the built-in scenes' light and camera.
    - ``"close"``: the same scene seen from above, framed on the mesh and
      its shadow (the view the real-mesh accuracy tests use).
    - ``"wide_floor"``: the mesh scaled to 1.5 units on a 6 x 6 slab with
      the light 3 units above the floor, seen from above the floor's front:
      a floor wider than the light is high. The light stands over the
      floor's middle, so every floor corner lies within 60 degrees of the
      shadow map's axis and one frustum covers it (``wide_floor`` below
      needs cube faces).
    """
    if setup not in SETUPS:
        raise ParameterError(f"unknown setup {setup!r}; choose one of {list(SETUPS)}")
    mesh = _resting(path, 1.5 if setup == "wide_floor" else 2.5)
    if setup == "wide_floor":
        light = SphereLight(center=(0.4, 3.0, 0.3), radius=light_radius, intensity=20.0)
        camera = Camera(eye=(0.0, 4.0, 4.4), target=(-0.2, 0.0, -0.2), fov_y=55.0, width=width, height=height)
        return Scene([ground_slab(half_size=3.0), mesh], light, camera, name=mesh.name)
    if setup == "close":
        camera = Camera(eye=(1.2, 6.5, 5.0), target=(-0.7, 0.4, -0.6), fov_y=50.0, width=width, height=height)
    else:
        camera = _camera().with_size(width, height)
    return Scene([ground_slab(), mesh], _light(light_radius), camera, name=mesh.name)


# The closed 2-manifold meshes of ../shared/meshes (its SOURCES.md), which the
# real-mesh accuracy suite and benchmarks/real_meshes.toml render.
CLOSED_MESHES = ("cube.obj", "spot.obj", "teapot-mcguire-closed.obj")
# (setup, light radius) per real-mesh scene: two radii seen close, and the wide floor.
SUITE_SETUPS = (("close", 0.3), ("close", 0.8), ("wide_floor", 0.3))


def real_mesh_suite(folder: str, *, width: int = 160, height: int = 160, meshes: tuple[str, ...] = CLOSED_MESHES) -> dict[str, Scene]:
    """The real-mesh scenes of the accuracy suite: every mesh of ``meshes``
    (files in ``folder``) in every (setup, light radius) of ``SUITE_SETUPS``,
    by name ``"<file> <setup> r=<radius>"``."""
    out = {}
    for mesh in meshes:
        for setup, radius in SUITE_SETUPS:
            scene = from_mesh(f"{folder}/{mesh}", width=width, height=height, light_radius=radius, setup=setup)
            out[f"{mesh} {setup} r={radius}"] = scene
    return out


def acute_caster(*, width: int = _WIDTH, height: int = _HEIGHT, light_radius: float = 0.3) -> Scene:
    """A thin triangular prism, 0.1 thick and 1.9 over an 8 x 8 slab, with a
    23-degree tip and two 78-degree corners, under a light at height 5: the
    acute silhouette vertex of penumbra wedges' 4.1 (Figure 7, ``acute_wedges``)."""
    pts = np.array([(-1.5, -0.6), (1.5, 0.0), (-1.5, 0.6)])
    v = np.vstack([np.c_[pts[:, 0], np.full(3, y), pts[:, 1]] for y in (1.9, 2.0)])
    # Outward: the bottom and top triangles, then the three sides.
    f = np.array([[0, 2, 1], [3, 4, 5], [0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4], [2, 0, 3], [2, 3, 5]])[:, ::-1]
    caster = Mesh(v, np.ascontiguousarray(f), object_id=1, name="prism")
    camera = Camera.look_at((0.0, 6.0, 3.0), (0.3, 0.0, 0.0), fov_y=45, width=width, height=height)
    return Scene([ground_slab(half_size=4.0), caster], SphereLight((0.0, 5.0, 0.0), light_radius, intensity=40.0), camera, name="acute_caster")


def wide_floor(path: str | None = None, *, width: int = _WIDTH, height: int = _HEIGHT, light_radius: float = 0.3) -> Scene:
    """A floor eight times wider than the light is high: a 12 x 12 slab under
    a light 1.5 above it, with a caster between them (the mesh file at
    ``path`` scaled to a 1-unit box, or a box). One shadow-map frustum would
    span 80 degrees to the floor's corners: shadow maps take cube faces
    (``projection="auto"``)."""
    caster = _resting(path, 1.0) if path is not None else box((0.0, 0.4, 0.0), (0.6, 0.8, 0.6), yaw_degrees=30.0)
    camera = Camera(eye=(0.0, 3.0, 7.0), target=(0.0, 0.3, 0.0), fov_y=50.0, width=width, height=height)
    light = SphereLight(center=(0.4, 1.5, 0.3), radius=light_radius, intensity=12.0)
    return Scene([ground_slab(half_size=6.0), caster], light, camera, name="wide_floor" + (f" ({caster.name})" if path else ""))


def cornell_box(path: str, *, width: int = _WIDTH, height: int = _HEIGHT, light_radius: float = 0.15) -> Scene:
    """The Cornell box of ``path`` (``CornellBox-Original.obj``: a 2-unit
    room, open at the front, with two blocks) lit by a sphere light under its
    ceiling, seen through the open front. The light is surrounded by
    geometry: shadow maps take cube faces (``projection="auto"``)."""
    loaded = load_mesh(path)
    room = Mesh(np.asarray(loaded.vertices), np.asarray(loaded.faces), albedo=0.7, object_id=1, name="cornell_box")
    camera = Camera(eye=(0.0, 1.0, 3.4), target=(0.0, 1.0, 0.0), fov_y=40.0, width=width, height=height)
    light = SphereLight(center=(0.0, 1.65, -0.1), radius=light_radius, intensity=3.0)
    return Scene([room], light, camera, name="cornell_box")


def sponza(path: str, *, width: int = _WIDTH, height: int = _HEIGHT, light_radius: float = 0.5) -> Scene:
    """Crytek's Sponza atrium (``sponza.obj``, 66k triangles) lit by a sphere
    light hanging in the atrium, seen from inside the building (the camera
    is inside the geometry's bounds). Shadow maps take cube faces."""
    loaded = load_mesh(path)
    hall = Mesh(np.asarray(loaded.vertices), np.asarray(loaded.faces), albedo=0.7, object_id=1, name="sponza")
    camera = Camera(eye=(-10.0, 2.5, 0.5), target=(4.0, 4.0, 0.0), fov_y=60.0, width=width, height=height)
    light = SphereLight(center=(0.0, 7.0, 0.0), radius=light_radius, intensity=150.0)
    return Scene([hall], light, camera, name="sponza")


def inverted_box(center: tuple[float, float, float], extents: tuple[float, float, float], *, name: str = "room", object_id: int = 0) -> Mesh:
    """A closed box whose faces point inwards: walls, floor and ceiling seen from inside."""
    walls = box(center, extents, name=name, object_id=object_id)
    return Mesh(walls.vertices, np.asarray(walls.faces)[:, ::-1], albedo=0.7, object_id=object_id, name=name, transform=walls.transform)


# --- The seeded scene generator (issue 28) ----------------------------------

#: ``get`` builds ``generate(seed)`` for the name ``"generated:<seed>"``.
GENERATED_PREFIX = "generated:"

#: The mesh files the generator draws from, relative to :func:`meshes_folder`:
#: every single-object mesh of ``../shared/meshes`` (not the Cornell box or
#: Sponza, which are rooms) and its whole ``corpus/``: closed, open (the
#: bunny, two scans, an aeroplane with cut-out windows), non-manifold (the
#: small bunny), 12 to 70k triangles.
GENERATOR_MESHES = (
    "cube.obj",
    "spot.obj",
    "teapot-mcguire-closed.obj",
    "bun_zipper.ply",
    "bun_zipper_res4.ply",
    "corpus/boot.obj",
    "corpus/cat-low-resolution.obj",
    "corpus/cow-low-resolution.obj",
    "corpus/demosthenes-low-res.obj",
    "corpus/fish_low_resolution.obj",
    "corpus/koala_low_resolution.obj",
    "corpus/mushroom.obj",
    "corpus/penguin.obj",
    "corpus/plane_holes.obj",
    "corpus/torus.obj",
)


def meshes_folder() -> Path | None:
    """The shared meshes: ``$PENUMBRA_MESHES`` when set, else the
    ``../shared/meshes`` beside the repository this package was loaded from;
    None when that folder does not exist."""
    env = os.environ.get("PENUMBRA_MESHES")
    folder = Path(env) if env else Path(__file__).resolve().parents[2].parent / "shared" / "meshes"
    return folder if folder.is_dir() else None


@functools.lru_cache(maxsize=32)
def _unit_mesh(path: str) -> tuple[np.ndarray, np.ndarray]:
    """A mesh file's vertices centred on their bounding box and scaled to a
    largest extent of 1, and its faces (read once per process)."""
    loaded = load_mesh(path)
    vertices = (np.asarray(loaded.vertices, dtype=np.float64) - loaded.bounds.mean(axis=0)) / float(np.max(loaded.extents))
    return vertices, np.asarray(loaded.faces)


@dataclass(frozen=True)
class GeneratedSpec:
    """What :func:`generate` drew for a seed; lengths in units of the main
    mesh's size (the largest extent of its bounding box), before ``scale``."""

    seed: int
    mesh: str
    #: Rotated about every axis (else about the vertical only).
    tumbled: bool
    #: Height of the mesh's lowest point above the floor (0: resting).
    lift: float
    light_radius: float
    #: Degrees above the horizon of the light's centre seen from the mesh's centre.
    elevation: float
    #: Distance from the mesh's centre to the light's centre.
    light_distance: float
    #: Half the floor's width over the light's height above the floor.
    floor_over_light_height: float
    #: A second mesh between the light and the first (their shadows overlap), or None.
    second_mesh: str | None
    room: bool
    #: Every length times this in the scene (10^-1 to 10^1.3).
    scale: float

    def describe(self) -> str:
        name = self.mesh.rsplit("/", 1)[-1].rsplit(".", 1)[0]
        parts = [name, f"r={self.light_radius:.2f}", f"elev={self.elevation:.0f}", f"floor={self.floor_over_light_height:.1f}h"]
        if self.lift > 0:
            parts.append(f"lift={self.lift:.2f}")
        if self.tumbled:
            parts.append("tumbled")
        if self.second_mesh:
            parts.append("+" + self.second_mesh.rsplit("/", 1)[-1].rsplit(".", 1)[0])
        if self.room:
            parts.append("room")
        return " ".join(parts)


def _draw(seed: int) -> GeneratedSpec:
    """The generator's choices for ``seed`` (numpy's PCG64, so the same on
    every machine)."""
    rng = np.random.default_rng([28, seed])
    mesh = str(rng.choice(GENERATOR_MESHES))
    tumbled = bool(rng.random() < 0.4)
    lift = 0.0 if rng.random() < 0.6 else float(rng.uniform(0.1, 1.0))
    light_radius = float(10 ** rng.uniform(-1.0, 0.0))
    elevation = float(rng.uniform(20.0, 90.0))
    light_distance = light_radius + float(rng.uniform(1.2, 3.5))
    floor = float(10 ** rng.uniform(0.0, math.log10(8.0)))
    second = str(rng.choice(GENERATOR_MESHES)) if rng.random() < 0.3 else None
    room = bool(rng.random() < 0.15)
    scale = float(10 ** rng.uniform(-1.0, 1.3))
    return GeneratedSpec(seed, mesh, tumbled, lift, light_radius, elevation, light_distance, floor, second, room, scale)


def _rotation(rng: np.random.Generator, tumbled: bool) -> np.ndarray:
    if tumbled:
        return trimesh.transformations.random_rotation_matrix(rand=rng.random(3))[:3, :3]
    return trimesh.transformations.rotation_matrix(float(rng.uniform(0, 2 * math.pi)), [0, 1, 0])[:3, :3]


def _placed(path: Path, rotation: np.ndarray, size: float) -> np.ndarray:
    """The mesh's vertices rotated, then scaled to a largest extent of
    ``size``, centred on their bounding box."""
    vertices, _ = _unit_mesh(str(path))
    v = vertices @ rotation.T
    v = v - (v.min(axis=0) + v.max(axis=0)) / 2
    return v * (size / float(np.max(v.max(axis=0) - v.min(axis=0))))


def _shadow_points(points: np.ndarray, light: np.ndarray, reach: float) -> np.ndarray:
    """``points`` projected from ``light`` onto the floor y = 0, each at most
    ``reach`` from the light's foot (points at or above the light go there)."""
    foot = np.array([light[0], 0.0, light[2]])
    out = []
    for p in points:
        drop = light[1] - p[1]
        # Below the light: the ray from the light through p meets y = 0 at
        # light + (p - light) * light_y / drop (drop > 0, so no division by zero).
        q = light + (p - light) * (light[1] / drop) if drop > 1e-9 else foot + np.array([p[0] - light[0], 0.0, p[2] - light[2]]) * 1e9
        d = q - foot
        length = float(np.linalg.norm(d))
        out.append(foot + d * (reach / length) if length > reach else q)
    return np.array(out)


def generate(seed: int, *, width: int = 256, height: int | None = None, folder: str | os.PathLike[str] | None = None) -> Scene:
    """A scene drawn from ``seed``: a mesh of :data:`GENERATOR_MESHES` (from
    ``folder``, default :func:`meshes_folder`) turned about the vertical or
    tumbled, resting on or floating over a closed floor slab, under a sphere
    light of radius 0.1-1 of the mesh's size at 20-90 degrees of elevation;
    the floor's half width 1-8 times the light's height (at least what holds
    the shadow); sometimes a second mesh between the light and the first, so
    that their shadows overlap; sometimes a room (an inverted box) around
    everything, the camera inside; the whole scene at a scale of 0.1-20 and
    moved off the origin. The camera frames the mesh and the near part of its
    shadow. The same seed gives the same scene everywhere; ``describe`` of
    :func:`generated_spec` says what was drawn, and the scene's name is
    ``"generated:<seed> <description>"``."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ParameterError(f"seed must be a non-negative integer, got {seed!r}")
    root = Path(folder) if folder is not None else meshes_folder()
    if root is None or not root.is_dir():
        raise ParameterError("generated scenes need the shared meshes: set PENUMBRA_MESHES or pass folder= (../shared/meshes beside the repository was not found)")
    spec = _draw(int(seed))
    rng = np.random.default_rng([28, int(seed), 1])
    height = width if height is None else height

    # The main mesh, its lowest point `lift` above the floor, centred over the origin.
    vertices = _placed(root / spec.mesh, _rotation(rng, spec.tumbled), 1.0)
    vertices[:, 1] += -vertices[:, 1].min() + max(spec.lift, 1e-3)
    centre = (vertices.min(axis=0) + vertices.max(axis=0)) / 2
    bound = float(np.linalg.norm(vertices - centre, axis=1).max())

    # The light: at `elevation` seen from the mesh's centre; its sphere clear
    # of the mesh's bounding sphere (light_distance >= radius + 1.2 > radius +
    # bound, since bound <= sqrt(3)/2) and of the floor.
    azimuth = float(rng.uniform(0, 2 * math.pi))
    e = math.radians(spec.elevation)
    direction = np.array([math.cos(e) * math.cos(azimuth), math.sin(e), math.cos(e) * math.sin(azimuth)])
    meshes_data = [(spec.mesh, vertices, 1)]
    distance = spec.light_distance
    second = None
    if spec.second_mesh is not None:
        size2 = float(rng.uniform(0.35, 0.7))
        v2 = _placed(root / spec.second_mesh, _rotation(rng, True), size2)
        bound2 = float(np.linalg.norm(v2, axis=1).max())
        # Between the two: clear of the first mesh's and the light's spheres.
        low, high_gap = bound + bound2 + 0.05, spec.light_radius + bound2 + 0.05
        distance = max(distance, low + high_gap + 0.2)
        at = centre + direction * float(rng.uniform(low, distance - high_gap))
        at[1] = max(at[1], bound2 + 0.02)  # above the floor
        second = (spec.second_mesh, v2 + at, 2)
    light = centre + direction * distance
    light[1] = max(light[1], spec.light_radius + 0.1)
    if second is not None:
        meshes_data.append(second)

    # The floor: wide enough for the shadow (to 6 units from the light's
    # foot) and `floor_over_light_height` times the light's height.
    everything = np.concatenate([v for _, v, _ in meshes_data])
    shadow = _shadow_points(everything[:: max(1, len(everything) // 2000)], light, 6.0)
    extent = np.concatenate([everything, shadow, light[None, :]])
    half = max(float(np.abs(extent[:, [0, 2]]).max()) * 1.1, spec.floor_over_light_height * float(light[1]))

    framed = np.concatenate([everything, _shadow_points(everything[:: max(1, len(everything) // 500)], light, 3.0)])
    target = (framed.min(axis=0) + framed.max(axis=0)) / 2
    radius = float(np.linalg.norm(framed - target, axis=1).max())
    if spec.room:
        lo = np.minimum(extent.min(axis=0), light - spec.light_radius) - float(rng.uniform(0.3, 1.5))
        hi = np.maximum(everything.max(axis=0), light + spec.light_radius) + float(rng.uniform(0.3, 1.5))
        lo[1] = 0.0
        lo[[0, 2]] = np.maximum(lo[[0, 2]], -half)
        hi[[0, 2]] = np.minimum(hi[[0, 2]], half)
        room_centre, room_size = (lo + hi) / 2, hi - lo
        # The camera inside, near a top corner on the side away from the light.
        corner = np.where(light > room_centre, lo, hi)
        eye = corner + (room_centre - corner) * 0.12
        eye[1] = lo[1] + room_size[1] * 0.75
        fov = 75.0
    else:
        fov = 45.0
        view = float(rng.uniform(25.0, 70.0))
        for turn in range(8):  # a view whose eye is clear of the light and the meshes
            psi = azimuth + math.pi + float(rng.uniform(-1.2, 1.2)) + turn * math.pi / 4
            eye = target + radius / math.sin(math.radians(fov / 2)) * 1.05 * np.array(
                [math.cos(math.radians(view)) * math.cos(psi), math.sin(math.radians(view)), math.cos(math.radians(view)) * math.sin(psi)]
            )
            if np.linalg.norm(eye - light) > spec.light_radius * 1.5 + 0.1:
                break

    # The whole scene moved off the origin and scaled.
    offset = np.array([float(rng.uniform(-3, 3)), 0.0, float(rng.uniform(-3, 3))])
    s = spec.scale

    def world(p: np.ndarray) -> np.ndarray:
        return (p + offset) * s

    meshes: list[Mesh] = []
    if spec.room:
        meshes.append(inverted_box(tuple(world(room_centre)), tuple(room_size * s), name="room", object_id=0))
    else:
        floor = ground_slab(half_size=half, thickness=0.1)
        meshes.append(Mesh(world(np.asarray(floor.vertices)), floor.faces, albedo=0.8, object_id=0, name="ground"))
    for path, v, object_id in meshes_data:
        _, faces = _unit_mesh(str(root / path))
        meshes.append(Mesh(world(v), faces, albedo=0.7, object_id=object_id, name=path.rsplit("/", 1)[-1]))
    # About 0.5 radiance on the floor under the light: albedo 0.8 / pi times
    # the irradiance pi * intensity * radius^2 / height^2.
    intensity = 0.625 * (float(light[1]) / spec.light_radius) ** 2
    camera = Camera(eye=tuple(world(eye)), target=tuple(world(target)), fov_y=fov, width=width, height=height)
    return Scene(meshes, SphereLight(tuple(world(light)), spec.light_radius * s, intensity=intensity), camera, name=f"{GENERATED_PREFIX}{seed} {spec.describe()}")


def generated_spec(seed: int) -> GeneratedSpec:
    """What :func:`generate` draws for ``seed``, without building the scene."""
    return _draw(int(seed))


def generated_suite(count: int, *, first: int = 0, width: int = 96, folder: str | os.PathLike[str] | None = None) -> dict[str, Scene]:
    """``count`` generated scenes, seeds ``first`` to ``first + count - 1``, by name."""
    out = {}
    for seed in range(first, first + count):
        scene = generate(seed, width=width, folder=folder)
        out[scene.name] = scene
    return out

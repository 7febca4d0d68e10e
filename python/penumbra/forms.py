"""One surface in the forms that files and exporters hand it over in (issue 27).

A closed mesh can arrive as a triangle soup (STL: every face its own three
corners, often with rounding), split into pieces, doubled, with reversed
windings or with slivers (zero-area and needle triangles) along its edges;
a whole scene can be mirrored or moved. SPEC section 3: each of these casts
the same shadow as the welded mesh. These functions build the forms, and
:func:`moved_fraction` measures how far an image moved; the invariance suite
(``tests/test_invariance.py``) holds every method to it.

Every form is seeded and deterministic.
"""

from __future__ import annotations

import numpy as np

from collections.abc import Callable

from .scene import Camera, Mesh, Scene, SphereLight

FORMS = ("soup", "split", "doubled", "reversed", "slivers", "mirrored", "translated")


def _size(vertices: np.ndarray) -> float:
    return float(np.max(np.ptp(vertices, axis=0)))


def _like(mesh: Mesh, vertices: np.ndarray, faces: np.ndarray, name: str) -> Mesh:
    return Mesh(vertices, faces, albedo=mesh.albedo, object_id=mesh.object_id, transform=mesh.transform, name=name)


def soup(mesh: Mesh, *, jitter: float = 1e-6, seed: int = 0) -> Mesh:
    """Every face with its own three corners, in shuffled order, each corner
    moved by up to ``jitter`` times the mesh's size (the largest side of its
    bounding box) in a random direction: an STL file written with rounding."""
    rng = np.random.default_rng(seed)
    faces = np.asarray(mesh.faces)[rng.permutation(len(mesh.faces))]
    corners = np.asarray(mesh.vertices, dtype=np.float64)[faces.reshape(-1)]
    direction = rng.normal(size=corners.shape)
    direction /= np.maximum(np.linalg.norm(direction, axis=1, keepdims=True), 1e-300)
    corners += direction * (rng.uniform(size=(len(corners), 1)) * jitter * _size(np.asarray(mesh.vertices)))
    return _like(mesh, corners, np.arange(len(corners)).reshape(-1, 3), f"{mesh.name} (soup)")


def split(mesh: Mesh, *, pieces: int = 3, seed: int = 0) -> list[Mesh]:
    """The faces in ``pieces`` meshes, cut by their centroids along a random
    direction, each with only the vertices it uses (so the cuts are open
    edges within each piece)."""
    rng = np.random.default_rng(seed)
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces)
    axis = rng.normal(size=3)
    order = np.argsort(vertices[faces].mean(axis=1) @ axis, kind="stable")
    out = []
    for k, part in enumerate(np.array_split(order, pieces)):
        used, inverse = np.unique(faces[part], return_inverse=True)
        out.append(_like(mesh, vertices[used], inverse.reshape(-1, 3), f"{mesh.name} (piece {k})"))
    return out


def doubled(mesh: Mesh) -> list[Mesh]:
    """The mesh and a second identical copy in the same place."""
    return [mesh, _like(mesh, mesh.vertices, mesh.faces, f"{mesh.name} (copy)")]


def reversed_windings(mesh: Mesh) -> Mesh:
    """Every face wound the other way (its front side is now the inside)."""
    return _like(mesh, mesh.vertices, np.asarray(mesh.faces)[:, ::-1], f"{mesh.name} (reversed)")


def with_slivers(mesh: Mesh, *, count: int = 40, seed: int = 0) -> Mesh:
    """The mesh with ``count`` degenerate triangles added along its edges, as
    scans carry them: half zero-area (an edge's two ends and its midpoint, a
    new vertex), half needles (an edge's two ends and a new vertex a
    millionth of the mesh's size from one of them)."""
    rng = np.random.default_rng(seed)
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces)
    size = _size(vertices)
    extra_vertices: list[np.ndarray] = []
    extra_faces: list[list[int]] = []
    for i, f in enumerate(rng.choice(len(faces), size=count, replace=count > len(faces))):
        k = int(rng.integers(3))
        a, b = int(faces[f][k]), int(faces[f][(k + 1) % 3])
        if i % 2 == 0:
            p = 0.5 * (vertices[a] + vertices[b])
        else:
            direction = rng.normal(size=3)
            p = vertices[a] + direction / max(float(np.linalg.norm(direction)), 1e-300) * 1e-6 * size
        extra_faces.append([a, b, len(vertices) + len(extra_vertices)])
        extra_vertices.append(p)
    return _like(mesh, np.vstack([vertices, extra_vertices]), np.vstack([faces, extra_faces]), f"{mesh.name} (slivers)")


_MIRROR = np.diag([-1.0, 1.0, 1.0])


def mirrored(scene: Scene) -> Scene:
    """The whole scene (meshes, light, camera) mirrored in the plane x = 0.
    Its image is the original's mirrored left to right (``np.fliplr``): the
    camera's right-hand axis flips with the world's x, and pixel centres are
    symmetric about the image's middle."""
    meshes = []
    for m in scene.meshes:
        t = np.eye(4)
        t[:3, :3] = _MIRROR
        meshes.append(Mesh(m.vertices, m.faces, albedo=m.albedo, object_id=m.object_id, transform=t @ np.asarray(m.transform, dtype=np.float64), normals=m.normals, name=m.name))
    return _moved(scene, meshes, lambda p: _MIRROR @ np.asarray(p, dtype=np.float64), lambda d: _MIRROR @ np.asarray(d, dtype=np.float64))


def translated(scene: Scene, offset: tuple[float, float, float]) -> Scene:
    """The whole scene (meshes, light, camera) moved by ``offset``; its image is the original's."""
    shift = np.asarray(offset, dtype=np.float64)
    meshes = []
    for m in scene.meshes:
        t = np.eye(4)
        t[:3, 3] = shift
        meshes.append(Mesh(m.vertices, m.faces, albedo=m.albedo, object_id=m.object_id, transform=t @ np.asarray(m.transform, dtype=np.float64), normals=m.normals, name=m.name))
    return _moved(scene, meshes, lambda p: np.asarray(p, dtype=np.float64) + shift, lambda d: np.asarray(d, dtype=np.float64))


def _moved(scene: Scene, meshes: list[Mesh], point: Callable[[object], np.ndarray], direction: Callable[[object], np.ndarray]) -> Scene:
    light = SphereLight(point(scene.light.center), scene.light.radius, intensity=scene.light.intensity)
    c = scene.camera
    assert c is not None, "a scene to move needs a camera"
    camera = Camera(eye=tuple(point(c.eye)), target=tuple(point(c.target)), up=tuple(direction(c.up)), fov_y=c.fov_y, width=c.width, height=c.height)
    return Scene(meshes, light, camera, ambient=scene.ambient, name=scene.name, metadata=dict(scene.metadata))


def replace_mesh(scene: Scene, index: int, forms: Mesh | list[Mesh]) -> Scene:
    """``scene`` with its mesh ``index`` replaced by ``forms`` (one mesh or several)."""
    replacement = forms if isinstance(forms, list) else [forms]
    meshes = list(scene.meshes[:index]) + replacement + list(scene.meshes[index + 1 :])
    return Scene(meshes, scene.light, scene.camera, ambient=scene.ambient, name=scene.name, metadata=dict(scene.metadata))


def moved_fraction(a: np.ndarray, b: np.ndarray, where: np.ndarray, threshold: float = 0.1) -> float:
    """The fraction of the pixels ``where`` at which images ``a`` and ``b``
    differ by more than ``threshold``."""
    mask = np.asarray(where, dtype=bool)
    if not mask.any():
        raise ValueError("no pixels to compare")
    return float(np.mean(np.abs(np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64))[mask] > threshold))

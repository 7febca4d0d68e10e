"""Rooms lit from inside (issue 31): scenes whose light is surrounded by
geometry, so that shadow maps take cube faces, and the measurement that holds
every method to the truth there and to itself under a rotation of the whole
scene (room, light and camera together).

- ``room_suite(size)``: every room scene by name, ``"<room> <light>"``: the
  6 x 4 x 6 room (an inverted box) with a pillar and a shelf, lit in its
  middle, 0.1 from a wall, 0.05 from a ceiling corner and close under the
  shelf; the Cornell box lit near its ceiling, a wall and the tall block
  (when its mesh file is given); a 3 x 3 x 8 corridor with a bench and a
  beam, lit in its middle and near its end wall.
- ``rotated(scene, x_degrees, y_degrees)``: the scene turned as one rigid
  body (rendered images match the unturned ones pixel for pixel, up to
  where the cube faces cut).
- ``measure(renderer, scenes, methods)``: per scene and method, the fraction
  of pixels off the truth (``reference`` at 1024 samples) by more than 0.1,
  and the fraction that moves by more than 0.1 under the rotation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Iterable, Mapping

import numpy as np

from penumbra.errors import MeshError
from penumbra.scene import Camera, Mesh, Scene, SphereLight
from penumbra.scenes import box, cornell_box, inverted_box

if TYPE_CHECKING:
    from penumbra.render import Renderer

__all__ = [
    "inverted_box",
    "room",
    "corridor",
    "cornell",
    "room_suite",
    "rotated",
    "RoomRow",
    "measure",
    "TRUTH_SAMPLES",
    "TRUTH_MAP_SIZE",
    "THRESHOLD",
    "ROTATION",
]

# The truth: `reference` at this many light samples (its noise at 64x64 moves
# 0.1% of pixels by more than THRESHOLD, issue 31).
TRUTH_SAMPLES = 1024
# ... with maps of this size: at 64x64 a pixel spans 6-12 map texels of a
# 512 face; against maps of 2048 (its default) the truth moves 0.0% of the
# ceiling-corner room's pixels by more than THRESHOLD, in a tenth of the time.
TRUTH_MAP_SIZE = 512
# A pixel is "off" (or "moved") when its visibility differs by more than this.
THRESHOLD = 0.1
# The rotation of the whole scene: degrees about x, then about y.
ROTATION = (30.0, 20.0)


# Lights of the 6 x 4 x 6 room (x and z in [-3, 3], y in [0, 4]): (centre, radius).
ROOM_LIGHTS: dict[str, tuple[tuple[float, float, float], float]] = {
    "middle": ((0.0, 2.0, 0.0), 0.25),
    "wall": ((2.9, 2.0, 0.5), 0.06),  # 0.1 from the wall x = 3
    "ceiling_corner": ((2.95, 3.95, 2.95), 0.03),  # 0.05 from the ceiling and both walls
    "under_shelf": ((-2.4, 1.42, 0.5), 0.08),  # 0.16 under the shelf's bottom
}


def room(light: str = "middle", *, size: int = 64) -> Scene:
    """The 6 x 4 x 6 room with a pillar and a shelf along the wall x = -3,
    the camera inside, lit by one of ``ROOM_LIGHTS``."""
    center, radius = ROOM_LIGHTS[light]
    meshes = [
        inverted_box((0.0, 2.0, 0.0), (6.0, 4.0, 6.0)),
        box((1.0, 1.5, -1.0), (0.6, 3.0, 0.6), name="pillar", object_id=1),
        # Its top (y = 1.62) well below the lights at y = 2: a top level with
        # the light's centre would be half lit, which no method of a map from
        # the centre sees.
        box((-2.38, 1.6, 0.5), (1.2, 0.04, 1.4), name="shelf", object_id=2),
    ]
    camera = Camera(eye=(-2.2, 3.0, 2.6), target=(0.8, 0.6, -1.0), fov_y=80.0, width=size, height=size)
    return Scene(meshes, SphereLight(center, radius, intensity=8.0), camera, name=f"room {light}")


CORRIDOR_LIGHTS: dict[str, tuple[tuple[float, float, float], float]] = {
    "middle": ((0.0, 2.4, -0.5), 0.15),
    "end_wall": ((0.4, 1.6, -3.9), 0.05),  # 0.1 from the end wall z = -4
}


def corridor(light: str = "middle", *, size: int = 64) -> Scene:
    """A 3 x 3 x 8 corridor (x in [-1.5, 1.5], y in [0, 3], z in [-4, 4])
    with a bench along one wall and a beam across the ceiling, seen from one
    end, lit by one of ``CORRIDOR_LIGHTS``."""
    center, radius = CORRIDOR_LIGHTS[light]
    meshes = [
        inverted_box((0.0, 1.5, 0.0), (3.0, 3.0, 8.0), name="corridor"),
        box((-1.1, 0.25, -1.5), (0.6, 0.5, 2.0), name="bench", object_id=1),
        box((0.0, 2.6, -2.0), (2.9, 0.3, 0.3), name="beam", object_id=2),
    ]
    camera = Camera(eye=(0.6, 2.0, 3.6), target=(-0.2, 0.6, -2.0), fov_y=70.0, width=size, height=size)
    return Scene(meshes, SphereLight(center, radius, intensity=4.0), camera, name=f"corridor {light}")


CORNELL_LIGHTS: dict[str, tuple[tuple[float, float, float], float]] = {
    "ceiling": ((0.3, 1.9, 0.4), 0.05),  # 0.09 under the ceiling (y = 1.99)
    "wall": ((-0.88, 1.0, 0.3), 0.05),  # 0.12 from the left wall
    "tall_block": ((0.12, 0.7, -0.24), 0.05),  # 0.12 from the tall block's right face
}


def cornell(path: str, light: str = "ceiling", *, size: int = 64) -> Scene:
    """The Cornell box of ``path`` (``penumbra.scenes.cornell_box``) lit by one of ``CORNELL_LIGHTS``."""
    center, radius = CORNELL_LIGHTS[light]
    scene = cornell_box(path, width=size, height=size)
    return replace(scene, light=SphereLight(center, radius, intensity=1.5), name=f"cornell {light}")


def room_suite(size: int = 64, cornell_path: str | None = None) -> dict[str, Scene]:
    """Every room scene by name: the room's four lights, the corridor's two
    and, given the Cornell box's mesh file, its three."""
    scenes = [room(light, size=size) for light in ROOM_LIGHTS]
    scenes += [corridor(light, size=size) for light in CORRIDOR_LIGHTS]
    if cornell_path is not None:
        scenes += [cornell(cornell_path, light, size=size) for light in CORNELL_LIGHTS]
    return {s.name: s for s in scenes}


def _rotation(x_degrees: float, y_degrees: float) -> np.ndarray:
    """The rotation about x by ``x_degrees``, then about y by ``y_degrees``."""
    a, b = math.radians(x_degrees), math.radians(y_degrees)
    rx = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
    return ry @ rx


def rotated(scene: Scene, x_degrees: float = ROTATION[0], y_degrees: float = ROTATION[1]) -> Scene:
    """``scene`` turned about the origin as one rigid body: every mesh (by its
    transform), the light's centre and the camera (eye, target and up)."""
    r = _rotation(x_degrees, y_degrees)
    r4 = np.eye(4)
    r4[:3, :3] = r
    turn = lambda p: tuple(float(x) for x in r @ np.asarray(p, dtype=np.float64))  # noqa: E731
    meshes = [
        Mesh(m.vertices, m.faces, albedo=m.albedo, object_id=m.object_id, transform=r4 @ np.asarray(m.transform, dtype=np.float64), normals=m.normals, name=m.name)
        for m in scene.meshes
    ]
    light = SphereLight(turn(scene.light.center), scene.light.radius, intensity=scene.light.intensity)
    camera = None
    if scene.camera is not None:
        c = scene.camera
        camera = Camera(turn(c.eye), turn(c.target), turn(c.up), fov_y=c.fov_y, width=c.width, height=c.height)
    return replace(scene, meshes=meshes, light=light, camera=camera, name=f"{scene.name} rotated")


@dataclass(frozen=True)
class RoomRow:
    """One scene and method: ``off`` the fraction of geometry pixels off the
    truth by more than ``THRESHOLD``, ``off_rotated`` the same in the rotated
    scene, ``moved`` the fraction that moves by more than ``THRESHOLD`` under
    the rotation, ``truth_moved`` the truth's own; None where the method
    refuses the scene (``refused`` says why)."""

    scene: str
    method: str
    off: float | None
    off_rotated: float | None
    moved: float | None
    truth_moved: float
    refused: str = ""


def _fraction(a: np.ndarray, b: np.ndarray, mask: np.ndarray) -> float:
    # Every room scene's camera sees geometry: mask.sum() > 0.
    return float((np.abs(a - b) > THRESHOLD)[mask].mean())


def measure(
    renderer: "Renderer",
    scenes: Mapping[str, Scene],
    methods: Iterable[str],
    *,
    params: Mapping[str, Mapping[str, Any]] | None = None,
    truth_samples: int = TRUTH_SAMPLES,
    truth_map_size: int = TRUTH_MAP_SIZE,
    rotation: tuple[float, float] = ROTATION,
    images: dict[tuple[str, str, bool], np.ndarray] | None = None,
) -> list[RoomRow]:
    """Renders every scene of ``scenes`` and its ``rotated`` copy with
    ``reference`` at ``truth_samples`` with maps of ``truth_map_size`` (the truth) and with every method of
    ``methods`` (each with ``params[method]``, its defaults otherwise), and
    returns a row per scene and method. A method that refuses a scene with a
    ``MeshError`` (PVM and PVMF take only 2-manifold casters) gets a row of
    None. ``images``, when given, receives every visibility image by
    (scene, method or "truth", rotated) and the pixels that see geometry
    (scene, "geometry", False), and truths already in it are taken
    from it instead of rendered."""
    params = params or {}
    methods = list(methods)
    rows = []
    for name, scene in scenes.items():
        turned = rotated(scene, *rotation)
        keys = [(name, "truth", False), (name, "truth", True), (name, "geometry", False)]
        if images is not None and all(k in images for k in keys):
            truth = [images[k] for k in keys]
        else:
            renders = [renderer.render(s, "reference", n_samples=truth_samples, map_size=truth_map_size, outputs=["visibility", "object_id"]) for s in (scene, turned)]
            geometry = (renders[0].object_id >= 0) & (renders[1].object_id >= 0)
            truth = [renders[0].visibility, renders[1].visibility, geometry.astype(np.float32)]
        # The pixels that see geometry in both (the Cornell box's open front
        # shows some background).
        mask = truth[2] > 0.5
        truth_moved = _fraction(truth[0], truth[1], mask)
        if images is not None:
            images.update(zip(keys, truth))
        for method in methods:
            try:
                v = [renderer.render(s, method, outputs=["visibility"], **params.get(method, {})).visibility for s in (scene, turned)]
            except MeshError as e:
                rows.append(RoomRow(name, method, None, None, None, truth_moved, refused=str(e)))
                continue
            if images is not None:
                images[(name, method, False)], images[(name, method, True)] = v
            rows.append(
                RoomRow(
                    name,
                    method,
                    off=_fraction(v[0], truth[0], mask),
                    off_rotated=_fraction(v[1], truth[1], mask),
                    moved=_fraction(v[0], v[1], mask),
                    truth_moved=truth_moved,
                )
            )
    return rows

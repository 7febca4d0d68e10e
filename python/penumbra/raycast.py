"""Exact visibility of the light's centre by ray casting on the CPU (numpy).

An independent check of shadow-map methods at radius 0: for each surface
point, is the segment to the light's centre blocked by any triangle? Cost is
points x triangles, so use it on small images or few points.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from penumbra.scene import Scene, world_geometry

__all__ = ["world_triangles", "point_light_visibility", "outline_band", "point_light_errors"]


def _world_meshes(scene: Scene) -> list[np.ndarray]:
    parts = []
    for mesh in scene.meshes:
        world = world_geometry(mesh)
        parts.append(world.vertices[world.faces])
    return parts


def world_triangles(scene: Scene) -> np.ndarray:
    """All triangles of the scene in world space, float64 (T, 3, 3)."""
    return np.concatenate(_world_meshes(scene))


def _segments_hit(origins: np.ndarray, light: np.ndarray, triangles: np.ndarray, chunk: int) -> np.ndarray:
    """Whether each segment origin -> light crosses any triangle (Moller-Trumbore)."""
    hit_any = np.zeros(len(origins), dtype=bool)
    a, e1, e2 = triangles[:, 0], triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]
    for start in range(0, len(origins), chunk):
        o = origins[start : start + chunk, None, :]
        d = light - o  # segment: o + t d, t in (0, 1)
        pvec = np.cross(d, e2[None])
        det = (e1[None] * pvec).sum(-1)
        # Segments parallel to a triangle's plane (det ~ 0) cannot cross it.
        ok = np.abs(det) > 1e-14
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        tvec = o - a[None]
        u = (tvec * pvec).sum(-1) * inv
        qvec = np.cross(tvec, e1[None])
        v = (d * qvec).sum(-1) * inv
        t = (e2[None] * qvec).sum(-1) * inv
        hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0) & (t < 1)
        hit_any[start : start + chunk] = hit.any(axis=1)
    return hit_any


def point_light_visibility(scene: Scene, points: np.ndarray, normals: np.ndarray, *, chunk: int = 1024, offset: float = 1e-4) -> np.ndarray:
    """1.0 where the light's centre is above the point's horizon and the segment
    to it meets no triangle, else 0.0 (float64).

    Each segment starts ``offset`` (relative to the scene's size) along the
    normal, so the surface the point lies on does not hide it. Only segments
    that pass through a mesh's bounding sphere test that mesh's triangles."""
    meshes = _world_meshes(scene)
    light = np.asarray(scene.light.center, dtype=np.float64)
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    normals = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
    scale = max(float(np.ptp(m.reshape(-1, 3), axis=0).max()) for m in meshes)
    origins = points + normals * offset * scale
    blocked = np.zeros(len(points), dtype=bool)
    for triangles in meshes:
        corners = triangles.reshape(-1, 3)
        center = (corners.min(0) + corners.max(0)) / 2
        radius = np.linalg.norm(corners - center, axis=1).max()
        d = light - origins
        # Closest point of each segment to the bounding sphere's centre; the
        # segment length is > 0 because no surface touches the light.
        t = np.clip(((center - origins) * d).sum(-1) / (d * d).sum(-1), 0, 1)
        near = np.linalg.norm(origins + t[:, None] * d - center, axis=1) <= radius * (1 + 1e-9)
        candidates = near & ~blocked
        if candidates.any():
            blocked[candidates] = _segments_hit(origins[candidates], light, triangles, chunk)
    facing = ((light - points) * normals).sum(-1) > 0
    return np.where(facing & ~blocked, 1.0, 0.0)


def outline_band(mask: np.ndarray) -> np.ndarray:
    """Pixels within one pixel of the outline of a boolean image: those whose
    3x3 neighbourhood holds both values."""
    mask = np.asarray(mask, dtype=bool)
    padded = np.pad(mask, 1, mode="edge")
    h, w = mask.shape
    shifted = [padded[1 + di : 1 + di + h, 1 + dj : 1 + dj + w] for di in (-1, 0, 1) for dj in (-1, 0, 1)]
    return np.any([s != mask for s in shifted], axis=0)


def point_light_errors(result: Any, scene: Scene, exact: np.ndarray | None = None) -> dict[str, float]:
    """A point-light render against exact ray casting: the geometry pixels
    it shadows where the light's centre is visible (``acne``) and the
    reverse (``leak``), beyond and on the one-pixel band around the true
    shadow outline (resolution, not bias: ``_on_outline``). ``exact``: the
    ray-cast visibility of the geometry pixels (> 0.5), computed when not
    given. ``penumbra bench``'s ``columns = ["penumbra.raycast:point_light_errors"]``."""
    geometry = result.object_id >= 0
    if exact is None:
        exact = np.zeros(geometry.shape, dtype=bool)
        exact[geometry] = point_light_visibility(scene, result.position[geometry], result.normal[geometry]) > 0.5
    lit, band = result.visibility > 0.5, outline_band(exact)
    acne, leak = geometry & exact & ~lit, geometry & ~exact & lit
    return {"acne": float((acne & ~band).sum()), "leak": float((leak & ~band).sum()), "acne_on_outline": float((acne & band).sum()),
            "leak_on_outline": float((leak & band).sum()), "geometry_pixels": float(geometry.sum())}

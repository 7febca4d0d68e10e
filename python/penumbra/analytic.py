"""Closed forms used to check renders independently of any renderer:
camera rays from the camera's definition, their hits on the plane y = 0, and
the solid angle shared by two cones (a sphere occluder against a sphere light),
and with it the visibility of a sphere light over the plane under one sphere."""

from __future__ import annotations

import numpy as np

from penumbra.scene import Camera, Scene, SphereLight

__all__ = ["camera_rays", "plane_hits", "cap_overlap", "sphere_occluder_visibility", "sphere_over_plane_visibility"]


def camera_rays(camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """Origin and unit direction (H, W, 3) of each pixel centre's ray (SPEC 3)."""
    eye = np.asarray(camera.eye, dtype=np.float64)
    forward = np.asarray(camera.target, dtype=np.float64) - eye
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, np.asarray(camera.up, dtype=np.float64))
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    h, w = camera.height, camera.width
    t = np.tan(np.radians(camera.fov_y) / 2)
    x = (2 * (np.arange(w) + 0.5) / w - 1) * t * w / h
    y = (1 - 2 * (np.arange(h) + 0.5) / h) * t
    d = forward + x[None, :, None] * right + y[:, None, None] * up
    return eye, d / np.linalg.norm(d, axis=-1, keepdims=True)


def plane_hits(camera: Camera) -> np.ndarray:
    """World points where each pixel's ray meets the plane y = 0 (NaN where it does not)."""
    eye, d = camera_rays(camera)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -eye[1] / d[..., 1]
    t = np.where(t > 0, t, np.nan)
    return eye + t[..., None] * d


def cap_overlap(a1: np.ndarray, a2: np.ndarray, g: np.ndarray) -> np.ndarray:
    """Solid angle shared by two cones of half-angles a1, a2 whose axes are g
    apart (intersection of two spherical caps; the tests check it against sampling)."""
    c1, c2, cg = np.cos(a1), np.cos(a2), np.cos(g)
    s1, s2, sg = np.sin(a1), np.sin(a2), np.sin(np.maximum(g, 1e-12))
    with np.errstate(invalid="ignore", divide="ignore"):
        lens = (
            2 * np.pi
            - 2 * np.arccos(np.clip((cg - c1 * c2) / (s1 * s2), -1, 1))
            - 2 * c1 * np.arccos(np.clip((c2 - cg * c1) / (sg * s1), -1, 1))
            - 2 * c2 * np.arccos(np.clip((c1 - cg * c2) / (sg * s2), -1, 1))
        )
    inside = 2 * np.pi * (1 - np.cos(np.minimum(a1, a2)))
    return np.where(g >= a1 + a2, 0.0, np.where(g <= np.abs(a1 - a2), inside, lens))



def sphere_occluder_visibility(camera: Camera, light: SphereLight, center: tuple[float, float, float] | np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """The visible fraction of `light` from each pixel's point on the plane
    y = 0 beneath one sphere occluder (`center`, `radius`): 1 - overlap(light
    cone, occluder cone) / light cone; with those points (`plane_hits`)."""
    p = plane_hits(camera)
    to_light = np.asarray(light.center, float) - p
    to_occluder = np.asarray(center, float) - p
    dl = np.linalg.norm(to_light, axis=-1)
    do = np.linalg.norm(to_occluder, axis=-1)
    a_light = np.arcsin(light.radius / dl)
    a_occ = np.arcsin(np.clip(radius / do, 0, 1))
    g = np.arccos(np.clip((to_light * to_occluder).sum(-1) / (dl * do), -1, 1))
    return 1 - cap_overlap(a_light, a_occ, g) / (2 * np.pi * (1 - np.cos(a_light))), p


def sphere_over_plane_visibility(scene: Scene, hit_distance: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The closed-form visibility of `scenes.sphere_over_plane` per pixel
    (`sphere_occluder_visibility`), and the pixels where it holds: on the
    plane, 0.1 inside its edge, and not hidden from the camera by the sphere
    (`hit_distance`, the distance to the camera ray's first hit, is the plane's)."""
    from penumbra.scenes import SPHERE_OCCLUDER

    assert scene.camera is not None
    closed, p = sphere_occluder_visibility(scene.camera, scene.light, *SPHERE_OCCLUDER)
    on_plane = np.isfinite(p[..., 0]) & (np.abs(p[..., 0]) < 4.9) & (np.abs(p[..., 2]) < 4.9)
    seen = on_plane & (np.abs(hit_distance - np.linalg.norm(p - np.asarray(scene.camera.eye), axis=-1)) < 1e-3)
    return closed, seen

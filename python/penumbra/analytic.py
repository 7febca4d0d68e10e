"""Closed forms used to check renders independently of any renderer:
camera rays from the camera's definition, their hits on the plane y = 0, and
the solid angle shared by two cones (a sphere occluder against a sphere light)."""

from __future__ import annotations

import numpy as np

from penumbra.scene import Camera

__all__ = ["camera_rays", "plane_hits", "cap_overlap"]


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

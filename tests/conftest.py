"""Shared fixtures: one renderer per session (device creation on lavapipe is
slow), skipped with the reason when no GPU adapter exists."""

from __future__ import annotations

import numpy as np
import pytest

import penumbra


@pytest.fixture(scope="session")
def renderer() -> penumbra.Renderer:
    try:
        return penumbra.Renderer()
    except penumbra.GpuUnavailableError as e:
        pytest.skip(f"no GPU adapter: {e}")


def camera_rays(camera: penumbra.Camera) -> tuple[np.ndarray, np.ndarray]:
    """Origin and unit direction (H, W, 3) of each pixel centre's ray, computed
    independently of the renderer from the camera's definition (SPEC 3)."""
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


def plane_hits(camera: penumbra.Camera) -> np.ndarray:
    """World points where each pixel's ray meets the plane y = 0 (NaN where it does not)."""
    eye, d = camera_rays(camera)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -eye[1] / d[..., 1]
    t = np.where(t > 0, t, np.nan)
    return eye + t[..., None] * d

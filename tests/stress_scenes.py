"""Scenes and checks shared by the stress suites (issue 8): small images and
maps, every implemented method with parameters that keep lavapipe quick."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

import penumbra

SIZE = 32
MAP = 256

# Per method: parameters that keep a render cheap on lavapipe (reference:
# 16 light samples instead of 256).
FAST: dict[str, dict[str, Any]] = {
    "hard": {"map_size": MAP},
    "pcf": {"map_size": MAP},
    "pcss": {"map_size": MAP},
    "pvm": {"map_size": MAP},
    # n_blur is in pixels: the default 12 spans a whole shadow at 32 px.
    "pvmf": {"map_size": MAP, "n_blur": 2},
    "reference": {"map_size": MAP, "n_samples": 16},
}
METHODS = list(FAST)

MESHES = Path(__file__).resolve().parents[1] / ".." / "shared" / "meshes"


def check_images(result: penumbra.RenderResult, what: str = "") -> None:
    """No NaN or Inf in any image; visibility in [0, 1]; radiance >= 0."""
    for key, image in result.images.items():
        assert np.isfinite(image).all(), f"{what}: non-finite values in {key}"
    v = result.visibility
    assert v.min() >= 0.0 and v.max() <= 1.0, f"{what}: visibility outside [0, 1]: {v.min()}, {v.max()}"
    assert result.radiance.min() >= 0.0, f"{what}: negative radiance"


def camera(eye: tuple[float, float, float] = (0.0, 4.0, 6.0), target: tuple[float, float, float] = (0.0, 0.5, 0.0), size: int = SIZE) -> penumbra.Camera:
    return penumbra.Camera(eye=eye, target=target, fov_y=45.0, width=size, height=size)


def mesh(vertices: Any, faces: Any, name: str, object_id: int = 1) -> penumbra.Mesh:
    return penumbra.Mesh(np.asarray(vertices, dtype=np.float64), np.asarray(faces), albedo=0.7, object_id=object_id, name=name)

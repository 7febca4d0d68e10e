"""Scenes and checks shared by the stress suites (issue 8): small images and
maps, every implemented method with parameters that keep lavapipe quick."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Iterator

import numpy as np
import pytest

import penumbra

SIZE = 32
MAP = 256

# Every registered method, so that a method is stress-tested from the day it
# is registered. Its parameters keep a render cheap on lavapipe: a small map
# for every method that takes `map_size`, and per method what else is costly.
METHODS = penumbra.methods()
CHEAPER: dict[str, dict[str, Any]] = {
    # n_blur is in pixels: the default 12 spans a whole shadow at 32 px.
    "pvmf": {"n_blur": 2},
    # 16 light samples instead of 256.
    "reference": {"n_samples": 16},
    "triangle_masks": {"n_samples": 16},
}
FAST: dict[str, dict[str, Any]] = {
    m: {**({"map_size": MAP} if "map_size" in penumbra.method_info(m).defaults() else {}), **CHEAPER.get(m, {})} for m in METHODS
}
# Methods that build silhouettes from mesh topology (they take `open_edges`).
VOLUME_METHODS = {m for m in METHODS if "open_edges" in penumbra.method_info(m).defaults()}
# A method of SPEC section 4 not implemented yet, for the tests of its error
# (None once every method is).
NOT_YET = next((m for m in penumbra.methods(implemented_only=False) if m not in METHODS), None)

MESHES = Path(__file__).resolve().parents[1] / ".." / "shared" / "meshes"


def seeded_renders(renderer: penumbra.Renderer, scene: penumbra.Scene, method: str, **params: Any) -> tuple[penumbra.RenderResult, penumbra.RenderResult]:
    """`method`'s renders of `scene` with seed 3 and with seed 4, after
    checking that the seed fixes the image (a second render with seed 3 is
    identical to the first)."""
    a = renderer.render(scene, method, seed=3, **params)
    b = renderer.render(scene, method, seed=3, **params)
    np.testing.assert_array_equal(a.visibility, b.visibility)
    return a, renderer.render(scene, method, seed=4, **params)


def new_renderer(**options: Any) -> penumbra.Renderer:
    """A renderer with `options`, or the test skipped, with the reason, on a
    machine without a GPU adapter."""
    try:
        return penumbra.Renderer(**options)
    except penumbra.GpuUnavailableError as e:
        pytest.skip(f"no GPU adapter: {e}")


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


def builtin_scenes_against_truth(
    renderer: penumbra.Renderer, cache: Path, size: int, settings: dict[str, dict[str, Any]]
) -> Iterator[tuple[str, dict[str, dict[str, float]], penumbra.RenderResult, Any]]:
    """Every built-in scene at `size` x `size` against its Mitsuba ground
    truth (256 spp, cached under `cache`; the test skips without Mitsuba):
    per scene its name, `metrics.compare` of `hard` and of each setting of
    `settings` (label: method and parameters, ``{"method": ..., **params}``),
    the last setting's render, and the truth."""
    pm = pytest.importorskip("penumbra.mitsuba", reason="Mitsuba 3 is not installed")
    from penumbra import metrics

    for name in penumbra.scenes.names():
        scene = penumbra.scenes.get(name, width=size, height=size)
        gt = pm.ground_truth(scene, spp=256, cache_dir=cache)
        errors = {"hard": metrics.compare(renderer.render(scene, "hard"), gt)}
        result = None
        for label, setting in settings.items():
            params = dict(setting)
            result = renderer.render(scene, params.pop("method"), **params)
            errors[label] = metrics.compare(result, gt)
        assert result is not None
        yield name, errors, result, gt

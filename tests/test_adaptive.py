"""Method `adaptive`: Schwarzler et al.'s adaptive light-source sampling (issue 18)."""

from __future__ import annotations

import numpy as np
import pytest

import penumbra


@pytest.fixture(scope="module")
def cache(tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    return tmp_path_factory.mktemp("gt")


# A light of radius 1 over the default scene at 128 px: a penumbra wide
# enough on screen that every cell of the first two levels fails the test.
def big_light(size: int = 128) -> penumbra.Scene:
    return penumbra.scenes.get(width=size, height=size, light_radius=1.0)


def test_maps_grow_and_error_falls_with_max_depth(renderer: penumbra.Renderer, cache) -> None:  # type: ignore[no-untyped-def]
    """Measured (128 px, 1024-spp Mitsuba, penumbra RMSE; `pytest -s` prints
    them): max_depth 0-4 use 4, 9, 25, 75, 91 maps; the paper's Eq. 3
    weights give 0.149, 0.092, 0.044, 0.024, 0.026: the mixed depths of
    level 4 (16 maps in a few cells) raise the error a little. The area
    weights (beyond the paper) give 0.081, 0.033, 0.021, 0.021 for 1-4."""
    pm = pytest.importorskip("penumbra.mitsuba", reason="Mitsuba 3 is not installed")
    from penumbra import metrics

    scene = big_light()
    gt = pm.ground_truth(scene, spp=1024, cache_dir=cache, kinds=["visibility"])
    maps, errors, area = [], [], []
    for depth in range(5):
        result = renderer.render(scene, "adaptive", max_depth=depth)
        maps.append(result.stats["light_samples"])
        errors.append(metrics.compare(result, gt)["visibility_rmse_penumbra"])
        area.append(metrics.compare(renderer.render(scene, "adaptive", max_depth=depth, weights="area"), gt)["visibility_rmse_penumbra"])
    print(maps, errors, area)
    assert maps[0] == 4 and all(a < b for a, b in zip(maps, maps[1:])), maps
    assert all(a > b for a, b in zip(errors[:4], errors[1:4])), errors
    assert all(a > b for a, b in zip(area, area[1:])), area
    assert maps[-1] < 289, "cells whose corner maps agree are not split"


@pytest.mark.parametrize("depth", [1, 2])
def test_every_cell_split_is_the_full_regular_grid(renderer: penumbra.Renderer, depth: int) -> None:
    """tolerance=0 and every cell failing: the (2^d + 1)^2 maps of the
    regular grid with equal weights, as `reference` draws it on the disk."""
    scene = big_light()
    result = renderer.render(scene, "adaptive", max_depth=depth, tolerance=0)
    n = (2**depth + 1) ** 2
    assert result.stats["light_samples"] == n == result.stats["shadow_maps_rendered"]
    assert result.stats["cells_subdivided"] == sum(4**k for k in range(depth))
    assert result.stats["max_depth_reached"] == 1
    grid = renderer.render(scene, "reference", sampling="disk", jitter=False, n_samples=n, map_size=512)
    np.testing.assert_allclose(result.visibility, grid.visibility, atol=1e-6)


def test_point_light_is_hards_one_map(renderer: penumbra.Renderer) -> None:
    scene = penumbra.scenes.get("cube_on_plane", width=64, height=64, light_radius=0.0)
    result = renderer.render(scene, "adaptive", map_size=2048, max_depth=1)
    assert result.stats["light_samples"] == 1
    np.testing.assert_array_equal(result.visibility, renderer.render(scene, "hard").visibility)


def test_weights_sum_to_one(renderer: penumbra.Renderer) -> None:
    """Mixed subdivision depths (Eq. 3 weights 1/9 to 1/289): a pixel every
    map sees lit is exactly 1, one none sees is 0, and nothing leaves [0, 1]."""
    scene = big_light(96)
    result = renderer.render(scene, "adaptive", max_depth=4)
    depths = [k for k in range(5) if result.stats.get(f"maps_level{k}", 0) > 0]
    assert len(depths) >= 3, result.stats
    v = result.visibility
    geometry = result.object_id >= 0
    lit = v[geometry & (v > 0.999)]
    assert lit.size > 100 and np.abs(lit - 1.0).max() < 1e-5
    assert 0.0 <= v.min() and v.max() <= 1.0 + 1e-6


def test_deterministic(renderer: penumbra.Renderer) -> None:
    scene = big_light(64)
    renderer.clear_pass_cache()
    a = renderer.render(scene, "adaptive", max_depth=3)
    b = renderer.render(scene, "adaptive", max_depth=3)
    np.testing.assert_array_equal(a.visibility, b.visibility)
    reuse = ("reused_gbuffer", "reused_passes", "reused_geometry")
    assert a.stats == {**b.stats, **{k: a.stats[k] for k in reuse}}


def test_tolerance_and_comparison_scale_save_maps(renderer: penumbra.Renderer) -> None:
    scene = big_light()
    base = renderer.render(scene, "adaptive", max_depth=4).stats["light_samples"]
    tolerant = renderer.render(scene, "adaptive", max_depth=4, tolerance=50).stats["light_samples"]
    coarse = renderer.render(scene, "adaptive", max_depth=4, comparison_scale=0.5)
    assert tolerant < base and coarse.stats["light_samples"] < base
    assert (coarse.stats["comparison_width"], coarse.stats["comparison_height"]) == (64, 64)


def test_pcf_2x2_smooths(renderer: penumbra.Renderer) -> None:
    """The 2x2 bilinear comparison filter adds in-between values at every hard border."""
    scene = big_light(96)
    plain = renderer.render(scene, "adaptive", max_depth=2).visibility
    smooth = renderer.render(scene, "adaptive", max_depth=2, pcf_2x2=True).visibility
    assert len(np.unique(np.round(smooth, 5))) > len(np.unique(np.round(plain, 5)))
    assert 0.0 <= smooth.min() and smooth.max() <= 1.0 + 1e-6


def test_intermediates_and_stats_per_level(renderer: penumbra.Renderer) -> None:
    scene = big_light(64)
    result = renderer.render(scene, "adaptive", max_depth=3, comparison_scale=0.5, intermediates=True)
    s = result.stats
    tested = [k for k in range(3) if f"cells_tested_level{k}" in s]
    assert tested and tested[0] == 0
    sums0 = result.images["adaptive_sums_level0"]
    assert sums0.shape == (32, 32) and set(np.unique(sums0)) <= {0.0, 1.0, 2.0, 3.0, 4.0}
    for k in tested:
        mask = result.images[f"adaptive_failing_level{k}"]
        assert mask.shape == (32, 32)
        assert int(mask.sum()) == s[f"failing_texels_level{k}"]
        assert result.images[f"adaptive_sums_level{k}"].max() <= 4 * s[f"cells_tested_level{k}"]
    assert sum(s[f"maps_level{k}"] for k in range(4) if f"maps_level{k}" in s) == s["light_samples"]
    assert list(result.timings)[:2] == ["gbuffer", "level0"] and "evaluate" in result.timings


@pytest.mark.parametrize(
    "params, words",
    [
        ({"max_depth": 7}, "max_depth"),
        ({"max_depth": -1}, "max_depth"),
        ({"comparison_scale": 0.0}, "comparison_scale"),
        ({"comparison_scale": 1.5}, "comparison_scale"),
        ({"tolerance": -1}, "tolerance"),
        ({"max_depth": 5, "map_size": 2048}, r"try lower max_depth \(max_depth 4 keeps at most 289 maps\), a smaller map_size"),
        ({"pcf_2x2": "yes"}, "pcf_2x2"),
        ({"weights": "equal"}, "weights"),
    ],
)
def test_parameters_are_checked(renderer: penumbra.Renderer, params: dict, words: str) -> None:
    with pytest.raises(penumbra.ParameterError, match=words):
        renderer.render(penumbra.scenes.get(width=8, height=8), "adaptive", **params)

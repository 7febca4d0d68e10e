"""Method `reference`: averaged hard shadows from light samples (issue 6, in part)."""

from __future__ import annotations

import numpy as np
import pytest

import penumbra


@pytest.fixture(scope="module")
def cache(tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    return tmp_path_factory.mktemp("gt")


def test_converges_to_ground_truth_as_samples_grow(renderer: penumbra.Renderer, cache) -> None:  # type: ignore[no-untyped-def]
    pm = pytest.importorskip("penumbra.mitsuba", reason="Mitsuba 3 is not installed")
    from penumbra import metrics

    for name in penumbra.scenes.names():
        scene = penumbra.scenes.get(name, width=80, height=80)
        gt = pm.ground_truth(scene, spp=1024, cache_dir=cache)
        errors = [metrics.compare(renderer.render(scene, "reference", n_samples=n, map_size=1024), gt)["visibility_rmse_penumbra"] for n in (4, 16, 64, 256)]
        assert all(a > b for a, b in zip(errors, errors[1:])), (name, errors)
        # Measured at 128x128 on the default scene: 0.044, 0.020, 0.015 for 16, 64, 256.
        assert errors[-1] < 0.03, (name, errors)


def test_point_light_is_one_sample_and_equals_hard(renderer: penumbra.Renderer) -> None:
    scene = penumbra.scenes.get("cube_on_plane", width=64, height=64, light_radius=0.0)
    result = renderer.render(scene, "reference", n_samples=64)
    assert result.stats["light_samples"] == 1 == result.stats["shadow_maps_rendered"]
    np.testing.assert_array_equal(result.visibility, renderer.render(scene, "hard").visibility)


def test_seeded_and_stratified(renderer: penumbra.Renderer) -> None:
    scene = penumbra.scenes.get(width=48, height=48)
    renderer.clear_pass_cache()  # every pass runs, and is timed
    a = renderer.render(scene, "reference", n_samples=16, seed=3, map_size=512)
    b = renderer.render(scene, "reference", n_samples=16, seed=3, map_size=512)
    c = renderer.render(scene, "reference", n_samples=16, seed=4, map_size=512)
    np.testing.assert_array_equal(a.visibility, b.visibility)
    assert not np.array_equal(a.visibility, c.visibility)
    assert renderer.render(scene, "reference", n_samples=10, map_size=256).stats["light_samples"] == 12
    assert list(a.timings) == ["gbuffer", "light_samples", "shading", "readback"]
    # With n samples, visibility takes values on the 1/n grid.
    assert np.allclose(a.visibility * 16, np.round(a.visibility * 16), atol=1e-4)


# (Larger lights put some samples within 80 degrees of the geometry's edge: a SceneError, as for any light.)
@pytest.mark.parametrize("radius", [1e-4, 0.5, 1.5])
def test_finite_and_bounded_for_every_radius(renderer: penumbra.Renderer, radius: float) -> None:
    for name in penumbra.scenes.names():
        result = renderer.render(penumbra.scenes.get(name, width=32, height=32, light_radius=radius), "reference", n_samples=9, map_size=256)
        assert np.isfinite(result.radiance).all() and 0 <= result.visibility.min() and result.visibility.max() <= 1


@pytest.mark.parametrize("params, words", [({"n_samples": 0}, "n_samples"), ({"n_samples": 5000}, "n_samples"), ({"seed": -1}, "seed"), ({"n_samples": 2.5}, "integer")])
def test_parameters_are_checked(renderer: penumbra.Renderer, params: dict, words: str) -> None:
    with pytest.raises(penumbra.ParameterError, match=words):
        renderer.render(penumbra.scenes.get(width=8, height=8), "reference", **params)

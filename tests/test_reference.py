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
    # Rounded up to full grids: the disk's 4 x 3; the sphere's 9 cosine
    # samples (3 x 3 for 8) and 2 uniform ones (2 x 1 for ceil(10 / 8)).
    assert renderer.render(scene, "reference", n_samples=10, map_size=256, sampling="disk").stats["light_samples"] == 12
    assert renderer.render(scene, "reference", n_samples=10, map_size=256).stats["light_samples"] == 11
    assert list(a.timings) == ["gbuffer", "light_samples", "shading", "readback"]
    # With n equal-weight samples on the disk, visibility takes values on the 1/n grid.
    d = renderer.render(scene, "reference", n_samples=16, seed=3, map_size=512, sampling="disk")
    assert np.allclose(d.visibility * 16, np.round(d.visibility * 16), atol=1e-4)
    assert d.params["sampling"] == "disk" and a.params["sampling"] == "sphere"


def test_sphere_sampling_removes_the_disks_bias(renderer: penumbra.Renderer, cache) -> None:  # type: ignore[no-untyped-def]
    """The facing disk is an ellipse from receivers off its axis: its mean
    penumbra error keeps a sign as n grows; the sphere's solid-angle weights
    remove it. Measured by this test (80 px, 1024-spp ground truth, two seeds
    of 256 samples averaged; `pytest -s` prints them): mean signed error
    0.0080 (disk) against 0.0013 (sphere) on the default scene."""
    pm = pytest.importorskip("penumbra.mitsuba", reason="Mitsuba 3 is not installed")
    from penumbra import metrics

    scene = penumbra.scenes.get(width=80, height=80)
    gt = pm.ground_truth(scene, spp=1024, cache_dir=cache, kinds=["visibility"])
    region = metrics.penumbra_region(gt.visibility)
    bias = {}
    for sampling in ("disk", "sphere"):
        v = np.mean([renderer.render(scene, "reference", n_samples=256, map_size=1024, sampling=sampling, seed=s).visibility for s in (0, 1)], axis=0)
        bias[sampling] = float(np.mean(v[region] - gt.visibility[region]))
    print(bias)
    assert bias["disk"] > 0.004 and abs(bias["sphere"]) < bias["disk"] / 3, bias


# Larger lights put some samples within 80 degrees of the geometry's edge: a
# SceneError, as for any light. Sphere samples reach up to r nearer the scene
# than the disk's, so the disk goes further (1.5 on the built-in scenes).
@pytest.mark.parametrize(("radius", "sampling"), [(1e-4, "sphere"), (0.5, "sphere"), (0.75, "sphere"), (1.0, "disk"), (1.5, "disk")])
def test_finite_and_bounded_for_every_radius(renderer: penumbra.Renderer, radius: float, sampling: str) -> None:
    for name in penumbra.scenes.names():
        scene = penumbra.scenes.get(name, width=32, height=32, light_radius=radius)
        result = renderer.render(scene, "reference", n_samples=9, map_size=256, sampling=sampling)
        assert np.isfinite(result.radiance).all() and 0 <= result.visibility.min() and result.visibility.max() <= 1


def test_sphere_samples_beyond_one_shadow_map_frustum_take_cube_faces(renderer: penumbra.Renderer) -> None:
    """A light sample's map covers the casters (issue 30: not the floor), in
    one frustum where its texels are no coarser than a cube face's. Samples
    low on a large light over a plate see it wider: with the default
    projection they take cube faces (the samples above do not); the lowest,
    0.05 over the plate, sees it beyond one frustum's 80 degrees, and with
    projection="frustum" that is a clear error."""
    plate = penumbra.scenes.box((0.0, 1.0, 0.0), (2.0, 0.1, 2.0), name="plate", object_id=1)
    camera = penumbra.Camera(eye=(0.0, 4.0, 6.0), target=(0.0, 0.5, 0.0), fov_y=50.0, width=32, height=32)
    light = penumbra.SphereLight((0.0, 2.5, 0.0), 1.4, intensity=20.0)
    scene = penumbra.Scene([penumbra.scenes.ground_plane(), plate], light, camera)
    result = renderer.render(scene, "reference", n_samples=9, map_size=256)
    assert 0 < result.stats["cube_maps"] < result.stats["light_samples"], result.stats
    assert result.stats["shadow_map_faces"] < 6 * result.stats["cube_maps"] + result.stats["light_samples"], "faces that see nothing are skipped"
    assert np.isfinite(result.visibility).all()
    with pytest.raises(penumbra.SceneError, match="80 degrees"):
        renderer.render(scene, "reference", n_samples=9, map_size=256, projection="frustum")


@pytest.mark.parametrize("params, words", [({"n_samples": 0}, "n_samples"), ({"n_samples": 5000}, "n_samples"), ({"seed": -1}, "seed"), ({"n_samples": 2.5}, "integer"), ({"sampling": "square"}, "sampling")])
def test_parameters_are_checked(renderer: penumbra.Renderer, params: dict, words: str) -> None:
    with pytest.raises(penumbra.ParameterError, match=words):
        renderer.render(penumbra.scenes.get(width=8, height=8), "reference", **params)

"""Mitsuba ground truth of the same scene (issue 3): the export agrees with
Penumbra where both are exact, the visibility estimator agrees with a closed
form, and the cache, metrics, comparison and CLI work."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import penumbra
from penumbra import metrics
from penumbra.raycast import outline_band
from penumbra.scenes import box, sphere

from penumbra.analytic import cap_overlap, sphere_over_plane_visibility

mitsuba = pytest.importorskip("mitsuba", reason="Mitsuba 3 is not installed")
from penumbra import mitsuba as pm  # noqa: E402


@pytest.fixture(scope="module")
def cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("groundtruth")


def test_variant_is_llvm_where_a_usable_llvm_exists() -> None:
    assert pm.variant() in ("llvm_ad_rgb", "scalar_rgb")
    if pm._usable_llvm():
        assert pm.variant() == "llvm_ad_rgb"


def test_unshadowed_radiance_matches_within_half_a_percent(renderer: penumbra.Renderer, cache: Path) -> None:
    scene = penumbra.scenes.lit_plane()
    result = renderer.render(scene)
    gt = pm.ground_truth(scene, spp=64, kinds=["radiance"], cache_dir=cache)
    keep = ~metrics.silhouette_band(result.object_id)
    scale = metrics.lit_mean(gt.radiance, np.ones(result.visibility.shape))
    relative_rmse = metrics.rmse(result.radiance, gt.radiance, keep) / scale
    assert relative_rmse < 0.005, f"relative RMSE {relative_rmse:.4f}"
    assert keep.sum() > 0.5 * keep.size


def asymmetric_scene(size: tuple[int, int]) -> penumbra.Scene:
    # No ground: a tall box up-left and a small sphere down-right, floating
    # against the background, so any flip or shift moves silhouettes.
    meshes = [
        box((-1.2, 1.0, 0.0), (0.6, 1.6, 0.6), yaw_degrees=25, object_id=1),
        sphere((1.1, -0.6, 0.3), 0.45, subdivisions=3, object_id=2),
    ]
    light = penumbra.SphereLight((2.0, 4.0, 3.0), 0.0, intensity=50.0)
    camera = penumbra.Camera(eye=(0.3, 0.5, 6.0), target=(0.0, 0.0, 0.0), fov_y=45, width=size[0], height=size[1])
    return penumbra.Scene(meshes, light, camera)


def test_cameras_agree_without_flip_or_offset(renderer: penumbra.Renderer, cache: Path) -> None:
    scene = asymmetric_scene((96, 72))
    result = renderer.render(scene)
    gt = pm.ground_truth(scene, spp=4, kinds=["visibility"], cache_dir=cache)
    ours = result.object_id >= 0
    theirs = gt.images["hit_distance"] > 0

    def beyond_outline(candidate: np.ndarray) -> int:
        return int(((candidate != theirs) & ~outline_band(theirs)).sum())

    assert beyond_outline(ours) == 0
    assert beyond_outline(ours[:, ::-1]) > 100, "the scene is not symmetric left-right"
    assert beyond_outline(ours[::-1, :]) > 100, "the scene is not symmetric up-down"
    assert beyond_outline(np.roll(ours, 2, axis=1)) > 20 and beyond_outline(np.roll(ours, 2, axis=0)) > 20
    # Distance along each pixel's ray agrees with the G-buffer's positions.
    eye = np.asarray(scene.camera.eye)
    distance = np.linalg.norm(result.position - eye, axis=-1)
    both = ours & theirs & ~outline_band(theirs)
    np.testing.assert_allclose(distance[both], gt.images["hit_distance"][both], rtol=1e-4)


def test_hard_agrees_with_a_tiny_light_except_on_shadow_edges(renderer: penumbra.Renderer, cache: Path) -> None:
    for name in ("sphere_on_plane", "overlapping_casters"):
        scene = penumbra.scenes.get(name, width=96, height=96, light_radius=1e-3)
        result = renderer.render(scene)
        gt = pm.ground_truth(scene, spp=16, cache_dir=cache)
        lit = gt.visibility > 0.5
        wrong = (np.abs(result.visibility - gt.visibility) > 0.5) & ~outline_band(lit)
        assert not wrong.any(), f"{name}: {wrong.sum()} pixels off the shadow edges disagree"
        assert (~lit & (result.object_id == 0)).sum() > 100, "there is a shadow"
        # Radiance too, off silhouettes and shadow edges, up to the ground truth's noise.
        keep = ~metrics.silhouette_band(result.object_id) & ~outline_band(lit)
        assert metrics.rmse(result.radiance, gt.radiance, keep) / metrics.lit_mean(gt.radiance, gt.visibility) < 0.01


def test_cap_overlap_formula_matches_sampling() -> None:
    rng = np.random.default_rng(1)
    for a1, a2, g in [(0.2, 0.3, 0.25), (0.1, 0.5, 0.45), (0.3, 0.3, 0.1), (0.4, 0.2, 0.55), (0.2, 0.1, 0.05)]:
        n = 400_000
        ca = 1 - rng.random(n) * (1 - np.cos(a1))
        phi = 2 * np.pi * rng.random(n)
        sa = np.sqrt(1 - ca**2)
        inside = (sa * np.cos(phi) * np.sin(g) + ca * np.cos(g)) > np.cos(a2)
        expected = float(cap_overlap(np.array(a1), np.array(a2), np.array(g))) / (2 * np.pi * (1 - np.cos(a1)))
        assert inside.mean() == pytest.approx(expected, abs=4e-3)


def test_visibility_estimator_matches_the_closed_form(cache: Path) -> None:
    # A sphere occluder over a plane: the visible fraction of the light from a
    # plane point is 1 - overlap(light cone, occluder cone) / light cone.
    scene = penumbra.scenes.sphere_over_plane()
    gt = pm.ground_truth(scene, spp=256, seed=3, noise_seed=4, kinds=["visibility"], cache_dir=cache)
    # Plane pixels not hidden from the camera by the sphere, and the closed form there.
    closed, seen = sphere_over_plane_visibility(scene, gt.images["hit_distance"])
    region = seen & metrics.penumbra_region(closed)
    assert region.sum() > 300, "the penumbra is in view"
    error = metrics.rmse(gt.visibility, closed, region)
    noise = metrics.rmse(gt.visibility, gt.second.visibility, region) / np.sqrt(2)
    # The icosphere lies inside the true sphere by ~2e-5 of its radius: far below the noise.
    assert error < 2 * noise + 1e-3, f"RMSE {error:.5f} against noise {noise:.5f}"
    assert metrics.rmse(gt.visibility, closed, seen) < 2 * noise + 1e-3


def test_cache_hits_and_keys(cache: Path) -> None:
    scene = penumbra.scenes.get(width=32, height=24)
    first = pm.ground_truth(scene, spp=16, seed=5, cache_dir=cache)
    again = pm.ground_truth(scene, spp=16, seed=5, cache_dir=cache)
    assert not any(first.cached.values()) and all(again.cached.values())
    for key in first.images:
        np.testing.assert_array_equal(first.images[key], again.images[key])
    other_seed = pm.ground_truth(scene, spp=16, seed=6, cache_dir=cache)
    assert not any(other_seed.cached.values())
    moved = scene.with_light(scene.light.with_radius(0.4))
    assert not any(pm.ground_truth(moved, spp=16, seed=5, cache_dir=cache).cached.values())
    uncached = pm.ground_truth(scene, spp=16, seed=5, cache_dir=cache, cache=False)
    assert not any(uncached.cached.values())
    np.testing.assert_array_equal(uncached.visibility, first.visibility)


def test_metrics_report_noise_beside_every_error(renderer: penumbra.Renderer, cache: Path) -> None:
    scene = penumbra.scenes.get(width=64, height=64)
    result = renderer.render(scene)
    gt = pm.ground_truth(scene, spp=64, noise_seed=1, cache_dir=cache)
    m = metrics.compare(result, gt)
    for key in ("visibility_rmse", "visibility_rmse_penumbra", "visibility_max_error", "visibility_flip", "radiance_rmse_rel", "radiance_mae_rel"):
        assert np.isfinite(m[key]) and np.isfinite(m[f"noise_{key}"]), key
        assert m[key] > m[f"noise_{key}"], f"hard shadows are worse than the ground truth's noise in {key}"
    assert m["penumbra_pixels"] > 50
    # A ground truth compared with itself has no error.
    same = metrics.compare_images(gt.visibility, gt, radiance=gt.radiance, object_id=result.object_id)
    assert same["visibility_rmse"] == 0 and same["radiance_rmse_rel"] == 0 and same["visibility_flip"] == 0


def test_compare_writes_a_picture(renderer: penumbra.Renderer, cache: Path, tmp_path: Path) -> None:
    out = tmp_path / "cmp.png"
    c = penumbra.compare(penumbra.scenes.get("cube_on_plane", width=48, height=40), "hard", renderer=renderer, spp=16, cache_dir=cache, out=out)
    assert out.read_bytes()[:4] == b"\x89PNG" and out.stat().st_size > 10_000
    assert c.metrics["visibility_rmse"] > 0 and c.result.method == "hard"


def test_compare_cli(cache: Path, tmp_path: Path) -> None:
    out, report = tmp_path / "c.png", tmp_path / "m.json"
    done = subprocess.run(
        [sys.executable, "-m", "penumbra", "compare", "--method", "hard", "--width", "40", "--height", "32", "--spp", "16",
         "--cache-dir", str(cache), "--json", str(report), "-o", str(out)],
        capture_output=True, text=True, timeout=300,
    )
    assert done.returncode == 0, done.stderr
    # One method: the table, then every metric beside the ground truth's noise.
    assert "| hard |" in done.stdout and "visibility_rmse_penumbra" in done.stdout and "ground-truth noise" in done.stdout
    assert json.loads(report.read_text())["methods"][0]["metrics"]["visibility_rmse"] > 0
    assert out.exists()


def test_bad_ground_truth_arguments(cache: Path) -> None:
    scene = penumbra.scenes.get(width=8, height=8)
    with pytest.raises(penumbra.ParameterError, match="spp"):
        pm.ground_truth(scene, spp=0, cache_dir=cache)
    with pytest.raises(penumbra.ParameterError, match="kinds"):
        pm.ground_truth(scene, kinds=["albedo"], cache_dir=cache)
    with pytest.raises(penumbra.ParameterError, match="noise_seed"):
        pm.ground_truth(scene, spp=4, seed=2, noise_seed=2, cache_dir=cache)


def test_scalar_variant_refuses_visibility_clearly(tmp_path: Path) -> None:
    code = (
        "import penumbra\nfrom penumbra import mitsuba as pm\n"
        "s = penumbra.scenes.get(width=8, height=8)\n"
        "print(pm.variant())\n"
        "print(pm.ground_truth(s, spp=4, kinds=['radiance'], cache=False).radiance.shape)\n"
        "try:\n    pm.ground_truth(s, spp=4, kinds=['visibility'], cache=False)\n"
        "except penumbra.GroundTruthError as e:\n    print('refused:', e)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
                          env={**os.environ, "PENUMBRA_MITSUBA_VARIANT": "scalar_rgb"}, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[:2] == ["scalar_rgb", "(8, 8, 3)"]
    assert "refused:" in done.stdout and "llvm" in done.stdout

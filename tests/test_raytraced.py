"""Method `raytraced`: shadow rays through wgpu ray queries (issue 21).

Needs an adapter with ray queries (`penumbra info`: `ray_queries`; Mesa's
lavapipe from 24.1 on, which scripts/setup.sh installs on Debian 12). Without
them these tests skip with the reason, except in CI (`CI` set), where
setup.sh has installed one and a skip would hide a broken set-up. The test of
the typed error runs on every adapter.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest
import trimesh

import penumbra
from stress_scenes import new_renderer, seeded_renders
from penumbra import metrics
from penumbra.raycast import outline_band, point_light_visibility

MESHES = Path(__file__).resolve().parents[1] / ".." / "shared" / "meshes"


@pytest.fixture(scope="module")
def rt(renderer: penumbra.Renderer) -> penumbra.Renderer:
    """The session's renderer, where it has ray queries."""
    if not renderer.adapter_info.get("ray_queries"):
        reason = f"adapter {renderer.adapter_info['name']} ({renderer.adapter_info['driver_info']}) has no ray queries"
        if os.environ.get("CI"):
            pytest.fail(f"{reason}: scripts/setup.sh should have installed a lavapipe with them")
        pytest.skip(reason)
    return renderer


def test_missing_ray_queries_are_a_typed_error_naming_the_feature(monkeypatch: pytest.MonkeyPatch) -> None:
    # Forced by the environment variable on any adapter; the other methods still render.
    monkeypatch.setenv("PENUMBRA_DISABLE_RAY_QUERY", "1")
    renderer = new_renderer()
    assert renderer.adapter_info["ray_queries"] is False
    assert penumbra.adapter_info()["ray_queries"] is False
    scene = penumbra.scenes.get(width=32, height=32)
    with pytest.raises(penumbra.GpuFeatureError, match="EXPERIMENTAL_RAY_QUERY") as info:
        renderer.render(scene, "raytraced", n_samples=4)
    message = str(info.value)
    assert "VK_KHR_ray_query" in message and "PENUMBRA_DISABLE_RAY_QUERY" in message and renderer.adapter_info["name"] in message
    assert isinstance(info.value, penumbra.GpuUnavailableError)
    assert renderer.render(scene, "hard", map_size=256).visibility.max() == 1.0
    # Parameters are still checked first, as for every method.
    with pytest.raises(penumbra.ParameterError, match="n_samples"):
        renderer.render(scene, "raytraced", n_samples=0)


def test_info_lists_ray_queries(capsys: pytest.CaptureFixture[str]) -> None:
    from penumbra import cli

    try:
        penumbra.adapter_info()
    except penumbra.GpuUnavailableError as e:
        pytest.skip(f"no GPU adapter: {e}")
    assert cli.main(["info"]) == 0
    assert '"ray_queries":' in capsys.readouterr().out


def test_determinism_by_seed(rt: penumbra.Renderer) -> None:
    scene = penumbra.scenes.get("overlapping_casters", width=48, height=48)
    a, c = seeded_renders(rt, scene, "raytraced", n_samples=16)
    assert not np.array_equal(a.visibility, c.visibility)
    # Reference's sphere sampling, rounded up the same way: 16 -> 4 x 4 cosine + 2 x 1 uniform.
    assert a.stats["light_samples"] == 18 == rt.render(scene, "reference", n_samples=16, map_size=256).stats["light_samples"]
    assert a.stats["full_pixels"] == a.stats["geometry_pixels"] and a.stats["adaptive_samples"] == 0
    # (The G-buffer may come from the pass cache.)
    assert [p for p in a.timings if p != "gbuffer"] == ["acceleration", "shadow_rays", "shading", "readback"]
    assert 0.0 <= a.visibility.min() and a.visibility.max() <= 1.0
    # Adaptive mode is deterministic too (its pixel list is filled in any order).
    d = rt.render(scene, "raytraced", n_samples=64, adaptive=True, seed=3)
    np.testing.assert_array_equal(d.visibility, rt.render(scene, "raytraced", n_samples=64, adaptive=True, seed=3).visibility)


@pytest.mark.parametrize("name", penumbra.scenes.names())
def test_point_light_is_one_ray_and_equals_cpu_ray_casting(rt: penumbra.Renderer, name: str) -> None:
    scene = penumbra.scenes.get(name, width=64, height=64, light_radius=0.0)
    # The CPU caster offsets its rays by 1e-4 of the scene's size: with the same offset, every pixel agrees.
    same = rt.render(scene, "raytraced", n_samples=256, ray_offset=1e-4)
    assert same.stats["light_samples"] == 1
    geometry = same.object_id >= 0
    exact = np.zeros(geometry.shape)
    exact[geometry] = point_light_visibility(scene, same.position[geometry], same.normal[geometry])
    np.testing.assert_array_equal(same.visibility, exact)
    assert 0 < exact[geometry].mean() < 1, "the scene has shadows to get wrong"
    # With the default offset: no acne and no leak beyond the outline (`penumbra bench --config benchmarks/ray_offsets.toml`).
    default = rt.render(scene, "raytraced")
    wrong = geometry & ((default.visibility > 0.5) != (exact > 0.5)) & ~outline_band(exact > 0.5)
    assert not wrong.any(), f"{wrong.sum()} pixels disagree beyond the outline"
    # No ray offset: the surface hides itself (what the offset is for).
    acne = geometry & (exact > 0.5) & (rt.render(scene, "raytraced", ray_offset=0.0).visibility < 0.5)
    assert acne.sum() > 10, "without an offset the surfaces shadow themselves"
    # Adaptive mode with a point light: still one ray.
    adaptive = rt.render(scene, "raytraced", adaptive=True)
    assert adaptive.stats["adaptive_samples"] == 0 and adaptive.stats["light_samples"] == 1
    np.testing.assert_array_equal(adaptive.visibility, default.visibility)


def _unique_caster(offset: float) -> penumbra.Mesh:
    """A box whose content no other test uses: its BLAS is built here."""
    box = trimesh.creation.box(extents=(1.0, 0.6 + offset, 0.8))
    return penumbra.Mesh(box.vertices, box.faces, object_id=1, name="caster")


def test_instance_transforms_place_the_mesh_and_moving_it_builds_no_blas(rt: penumbra.Renderer) -> None:
    base = penumbra.scenes.get("cube_on_plane", width=64, height=64)
    caster = _unique_caster(0.0123)
    moved = np.eye(4)
    moved[:3, :3] = trimesh.transformations.rotation_matrix(0.4, (0, 1, 0))[:3, :3] * 1.2
    moved[:3, 3] = (0.3, 0.9, -0.2)
    placed = penumbra.Scene([base.meshes[0], penumbra.Mesh(caster.vertices, caster.faces, transform=moved, object_id=1)], base.light, base.camera)
    first = rt.render(placed, "raytraced", n_samples=64)
    assert first.stats["blas_built"] == 1 and first.stats["blas_reused"] == 1 and first.stats["tlas_built"] == 1
    # The same geometry with the transform applied to the vertices: the same shadow.
    world = (np.c_[caster.vertices, np.ones(len(caster.vertices))] @ moved.T)[:, :3]
    baked = penumbra.Scene([base.meshes[0], penumbra.Mesh(world, caster.faces, object_id=1)], base.light, base.camera)
    reference = rt.render(baked, "raytraced", n_samples=64)
    np.testing.assert_array_equal(first.object_id, reference.object_id)
    assert np.abs(first.visibility - reference.visibility).max() < 1e-3
    # Moving the mesh again: a new TLAS over the same BLAS, and a shadow elsewhere.
    moved[:3, 3] = (-0.6, 0.9, 0.4)
    again = penumbra.Scene([base.meshes[0], penumbra.Mesh(caster.vertices, caster.faces, transform=moved, object_id=1)], base.light, base.camera)
    second = rt.render(again, "raytraced", n_samples=64)
    assert second.stats["blas_built"] == 0 and second.stats["blas_reused"] == 2 and second.stats["tlas_built"] == 1
    assert np.abs(second.visibility - first.visibility).max() > 0.5


def test_acceleration_structures_are_reused_across_renders_and_counted(rt: penumbra.Renderer) -> None:
    base = penumbra.scenes.get("cube_on_plane", width=48, height=48)
    scene = penumbra.Scene([base.meshes[0], _unique_caster(0.0456)], base.light, base.camera)
    first = rt.render(scene, "raytraced", n_samples=16)
    assert first.stats["blas_built"] == 1 and first.stats["tlas_built"] == 1
    assert first.stats["acceleration_bytes"] > 0
    assert first.stats["acceleration_cache_bytes"] >= first.stats["acceleration_bytes"]
    # Another render of the same scene, with other parameters and light: nothing is built.
    moved_light = scene.with_light(penumbra.SphereLight((1.0, 5.0, 0.5), 0.4, intensity=60.0))
    for s, params in ((scene, {"n_samples": 64}), (scene, {"adaptive": True, "n_samples": 64}), (moved_light, {"n_samples": 16})):
        again = rt.render(s, "raytraced", **params)
        assert again.stats["blas_built"] == 0 and again.stats["blas_reused"] == 2 and again.stats["tlas_built"] == 0, params
        assert again.stats["acceleration_bytes"] == first.stats["acceleration_bytes"]
    # With the pass cache off the structures are still kept (as topology is).
    off = penumbra.Renderer(pass_cache=False)
    off.render(scene, "raytraced", n_samples=4)
    assert off.render(scene, "raytraced", n_samples=4).stats["blas_built"] == 0


def test_adaptive_mode_refines_only_the_penumbra_and_matches_plain_mode(rt: penumbra.Renderer) -> None:
    for name in penumbra.scenes.names():
        scene = penumbra.scenes.get(name, width=64, height=64)
        plain = rt.render(scene, "raytraced", n_samples=64)
        adaptive = rt.render(scene, "raytraced", n_samples=64, adaptive=True)
        geometry = adaptive.stats["geometry_pixels"]
        assert adaptive.stats["adaptive_samples"] == 16 and adaptive.stats["coarse_pixels"] == geometry
        assert 0 < adaptive.stats["full_pixels"] < 0.5 * geometry, name
        assert [p for p in adaptive.timings if p != "gbuffer"] == ["acceleration", "classify", "refine", "shading", "readback"]
        d = np.abs(adaptive.visibility - plain.visibility)
        # Refined pixels are plain mode's exactly; the rest kept a first-pass 0 or 1.
        kept = d > 0
        assert np.isin(adaptive.visibility[kept], [0.0, 1.0]).all(), name
        assert (d == 0).sum() >= adaptive.stats["full_pixels"], name
        # Misses (measured by `penumbra bench --config benchmarks/raytraced_adaptive.toml` at 128x128 with
        # 256 samples: 2 of the 10103 penumbra pixels of nine scenes at the defaults).
        region = metrics.penumbra_region(plain.visibility)
        assert (d > 0.01).sum() <= max(2, 0.01 * region.sum()), (name, (d > 0.01).sum(), region.sum())


def _truth_noise(a: np.ndarray, b: np.ndarray, region: np.ndarray) -> float:
    return metrics.rmse(a, b, region) / math.sqrt(2)


def _scenes(size: int) -> dict[str, penumbra.Scene]:
    out = {n: penumbra.scenes.get(n, width=size, height=size) for n in penumbra.scenes.names()}
    for name in ("spot.obj", "teapot-mcguire-closed.obj", "CornellBox-Original.obj"):
        if (MESHES / name).exists():
            make = penumbra.scenes.cornell_box if name.startswith("CornellBox") else penumbra.scenes.from_mesh
            out[name] = make(str(MESHES / name), width=size, height=size)
    return out


def test_unbiased_against_mitsuba_and_error_falls_with_samples(rt: penumbra.Renderer, tmp_path: Path) -> None:
    pm = pytest.importorskip("penumbra.mitsuba", reason="Mitsuba 3 is not installed")
    for name, scene in _scenes(48).items():
        gt = pm.ground_truth(scene, spp=1024, seed=0, noise_seed=1, kinds=["visibility"], cache_dir=tmp_path)
        region = metrics.penumbra_region(gt.visibility)
        gt_noise = _truth_noise(gt.visibility, gt.second.visibility, region)
        own = {}
        for n in (16, 256, 1024):
            a = rt.render(scene, "raytraced", n_samples=n, seed=0).visibility
            b = rt.render(scene, "raytraced", n_samples=n, seed=1).visibility
            own[n] = _truth_noise(a, b, region)
            if n == 1024:
                error = metrics.rmse(a, gt.visibility, region)
                combined = math.hypot(gt_noise, own[n])
                # No bias: the error is the two estimators' noise (ratios 0.93-1.31
                # at 96x96 in `penumbra bench --config benchmarks/raytraced_accuracy.toml`).
                assert error < 1.5 * combined, (name, error, gt_noise, own[n])
        # 1/sqrt(n) would divide the noise by 4 from 16 to 256 samples; stratification does better.
        assert own[16] / own[256] > 3.0, (name, own)


def test_compare_and_sweep_take_raytraced_as_truth(rt: penumbra.Renderer, tmp_path: Path) -> None:
    scene = penumbra.scenes.get(width=40, height=40)
    c = penumbra.compare(scene, "pcss", renderer=rt, truth="raytraced", spp=256, out=tmp_path / "c.png")
    assert c.ground_truth.variant == "raytraced" and c.ground_truth.second is not None
    assert c.ground_truth.spp == 256
    assert c.ground_truth.extra["light_samples"] == rt.render(scene, "raytraced", n_samples=256).stats["light_samples"] == 261
    assert c.metrics["noise_visibility_rmse_penumbra"] > 0 and c.metrics["visibility_rmse_penumbra"] > c.metrics["noise_visibility_rmse_penumbra"]
    assert (tmp_path / "c.png").stat().st_size > 0
    # The truth against itself at another seed: at its noise floor.
    same = penumbra.compare(scene, "raytraced", renderer=rt, truth="raytraced", spp=256, seed=5, noise_seed=6, n_samples=256)
    assert same.metrics["visibility_rmse_penumbra"] < 3 * same.metrics["noise_visibility_rmse_penumbra"]
    with pytest.raises(penumbra.ParameterError, match="truth"):
        penumbra.compare(scene, "hard", renderer=rt, truth="oracle")
    df = penumbra.sweep(scene, "pcss", {"filter_samples": [4, 16]}, ground_truth="raytraced", ground_truth_spp=64, renderer=rt, progress=False)
    assert len(df) == 2 and df["noise_visibility_rmse_penumbra"].notna().all() and df["visibility_rmse_penumbra"].notna().all()

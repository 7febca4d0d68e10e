"""Penumbra wedges (issue 19; Akenine-Möller & Assarsson 2002, 4.1-4.2)."""

from __future__ import annotations

import numpy as np
import pytest

import penumbra
from penumbra.scenes import box, ground_plane, ground_slab, sphere
from stress_scenes import FAST, builtin_scenes_against_truth, check_images
from test_degenerate_geometry import CASES
from test_pvm import disk_cut_visible_fraction, finned_box, long_edge_scene
from test_real_meshes import SUITE, check_against_truth, truth, truth_of  # noqa: F401 (truth: a fixture)

RADII = [0.0, 1e-4, 0.05, 0.5, 2.2]

# The 2002 paper's construction as the defaults were before issue 28: Eq.
# 1-3's interpolation, every wedge's term summed.
INTERPOLATION: dict[str, object] = {"intensity": "interpolation", "overlap": "sum", "map_samples": 0}


def ground_band(result: penumbra.RenderResult, columns: slice) -> np.ndarray:
    """Penumbra pixels (0.02 < v < 0.98) on the ground's +z half in `columns`."""
    v = result.visibility[:, columns]
    return (result.object_id[:, columns] == 0) & (result.position[:, columns, 2] > 0.0) & (v > 0.02) & (v < 0.98)


# Measured (this file's first commit, lavapipe, map 2048): the largest
# difference between wedges' Eq. 1-3 interpolation and the exact fraction of
# the disk the edge's plane cuts, over the penumbra of one long edge:
# 0.070 at r = 0.3, 0.094 at r = 0.8 (RMS 0.045, 0.053). Most of it is the
# shape of the falloff (linear across the wedge against the disk segment's
# S-curve: 0.055 at most between the two in the chord's offset); the rest
# grows with r / distance, as the planes through c -+ r n are not tangent to
# the sphere (4.1). The bounds leave a tenth for other drivers' rasterisers.
SINGLE_EDGE_BOUND = {0.3: (0.08, 0.05), 0.8: (0.10, 0.06)}
# The per-pixel coverage (the default) measures the disk's segment itself:
# 0.00022 and 0.0017 at most (RMS 0.00016, 0.0012) measured; bounded at 0.005
# (what is left: the tangent cone's radius in the plane through the centre
# against the disk of the light's radius that the reference takes).
COVERAGE_EDGE_BOUND = (0.005, 0.003)


@pytest.mark.parametrize("intensity", ["interpolation", "coverage"])
@pytest.mark.parametrize("radius", list(SINGLE_EDGE_BOUND))
def test_a_single_edge_follows_the_disk_cut_within_the_measured_tolerance(renderer: penumbra.Renderer, radius: float, intensity: str) -> None:
    scene = long_edge_scene(radius)
    result = renderer.render(scene, "wedges", intermediates=True, intensity=intensity, overlap="sum")
    columns = slice(70, 90)
    inside = ground_band(result, columns)
    p = result.position[:, columns][inside].astype(np.float64)
    assert len(p) > 200, "the columns cross the penumbra"
    k = disk_cut_visible_fraction(p, np.array([-4.0, 2.1, 1.5]), np.array([4.0, 2.1, 1.5]), scene.light.center.astype(float), radius, np.array([0.0, 2.0, 0.0]))
    assert k.min() < 0.1 and k.max() > 0.9, "the band spans the penumbra"
    error = result.visibility[:, columns][inside] - k
    worst, rms = SINGLE_EDGE_BOUND[radius] if intensity == "interpolation" else COVERAGE_EDGE_BOUND
    assert np.abs(error).max() <= worst and np.sqrt(np.mean(error**2)) <= rms, (np.abs(error).max(), np.sqrt(np.mean(error**2)))
    if intensity == "interpolation":
        # The interpolation is symmetric about the hard-shadow plane: too lit
        # on the umbra side, too dark on the lit side, by the S-curve's shape.
        assert error[k < 0.3].mean() > 0 > error[k > 0.7].mean()


def penumbra_width(result: penumbra.RenderResult) -> int:
    return int(ground_band(result, slice(70, 90)).sum())


def test_penumbra_widens_with_the_light_radius(renderer: penumbra.Renderer) -> None:
    widths = [penumbra_width(renderer.render(long_edge_scene(r), "wedges")) for r in (0.1, 0.3, 0.8)]
    assert 0 < widths[0] < widths[1] < widths[2], widths


def test_penumbra_widens_with_the_distance_from_occluder_to_receiver(renderer: penumbra.Renderer) -> None:
    base = long_edge_scene(0.5)
    widths = []
    for height in (1.0, 2.0, 3.0):
        bar = box((0.0, height, 0.0), (8.0, 0.2, 3.0), object_id=1, name="bar")
        widths.append(penumbra_width(renderer.render(penumbra.Scene([ground_slab(), bar], base.light, base.camera), "wedges")))
    assert 0 < widths[0] < widths[1] < widths[2], widths


@pytest.mark.parametrize("name", penumbra.scenes.names())
def test_radius_zero_is_hard_and_every_radius_stays_finite_in_0_1(renderer: penumbra.Renderer, name: str) -> None:
    for radius in RADII:
        scene = penumbra.scenes.get(name, width=64, height=64, light_radius=radius)
        result = renderer.render(scene, "wedges", intermediates=True)
        check_images(result, f"{name} r={radius}")
        # The wedges' own sum, without the map bound (checked below against the intensity).
        alone = renderer.render(scene, "wedges", intermediates=True, map_samples=0)
        s = result.stats
        if radius == 0:
            # A point light has no penumbra: no wedges, the shadow-map test alone.
            assert s["wedges"] == 0 and s["pixels_in_wedge"] == 0
            np.testing.assert_array_equal(result.visibility, renderer.render(scene, "hard").visibility)
        else:
            edges = s["silhouette_edges"] - s["light_parallel_edges"] - s["hidden_silhouette_edges"]
            assert s["wedges"] == edges + s["extra_wedges"], s
            # (At r = 1e-4 the wedges are thinner than a pixel.)
            assert s["pixels_in_wedge"] > 0 or radius < 0.05, s
            # Where the light's centre is above the surface, the signed
            # intensity before clamping is what was clamped (the horizon
            # repair only lowers it); below, the horizon's sliver is all.
            facing = ((scene.light.center - alone.position) * alone.normal).sum(-1) > 0
            assert (alone.visibility[facing] <= np.clip(alone["wedges_intensity"][facing], 0, 1) + 1e-6).all()


def test_intermediates_and_stats_explain_the_image(renderer: penumbra.Renderer) -> None:
    scene = long_edge_scene(0.5)
    result = renderer.render(scene, "wedges", intermediates=True, repairs="cone+hidden", map_samples=0)
    hard = renderer.render(scene, "hard").visibility
    intensity = result["wedges_intensity"]
    np.testing.assert_allclose(result.visibility, np.clip(intensity, 0, 1), atol=1e-6)
    # Outside every wedge the signed intensity is the hard term, and the hard term is `hard`.
    outside = intensity == result["wedges_hard"]
    assert outside.mean() > 0.5
    assert (result["wedges_hard"][outside] == hard[outside]).mean() > 0.999
    # A pixel whose intensity is not its hard term is inside a wedge.
    assert result.stats["pixels_in_wedge"] >= int((intensity != result["wedges_hard"]).sum()) > 0
    # repairs="cone+hidden": no horizon repair, so no object map.
    assert list(result.timings)[:4] == ["gbuffer", "shadow_map", "penumbra_wedges", "visibility"]


def test_pass_cache_reuses_the_wedges(renderer: penumbra.Renderer) -> None:
    scene = penumbra.scenes.get("overlapping_casters", width=48, height=48)
    renderer.clear_pass_cache()
    first = renderer.render(scene, "wedges", map_size=512)
    again = renderer.render(scene, "wedges", map_size=512)
    assert again.reused_passes == ["gbuffer", "object_map", "penumbra_wedges", "shadow_map", "solid_layers"]
    np.testing.assert_array_equal(first.visibility, again.visibility)
    # Another acute_wedges value rebuilds the wedges from cached silhouettes.
    other = renderer.render(scene, "wedges", map_size=512, acute_wedges=4)
    assert "penumbra_wedges" not in other.reused_passes
    # One topology and one silhouette per scene (connectivity spans its meshes).
    assert other.stats["silhouette_cache_hits"] == 1


@pytest.mark.parametrize("intensity", ["coverage", "interpolation"])
def test_the_tile_cull_skips_wedges_and_changes_no_pixel(renderer: penumbra.Renderer, intensity: str) -> None:
    """The tile cull (tile_cull.wgsl, issue 30) leaves out, per 8 x 8 pixels,
    wedges whose support holds none of their points: on a real mesh with a
    wide light and on the built-in scenes it skips at least a third of the
    (block, wedge) entries, and the image is the one with every wedge
    evaluated (measured: identical on 7 of 8 generated scenes at 256 x 256,
    87 pixels apart by at most 2.2e-6 on the eighth, where a projected edge
    grazes the light's disk)."""
    from penumbra import scenes

    cases = [scenes.get(name, width=64, height=64) for name in ("overlapping_casters", "sphere_on_plane")]
    if scenes.meshes_folder() is not None:
        cases += [scenes.generate(seed, width=96) for seed in (1, 27)]
    for scene in cases:
        # Every pixel computed: subsample's kappa counts the edges of a
        # pixel's list, so with every wedge listed it interpolates less.
        culled = renderer.render(scene, "wedges", intensity=intensity, subsample=0.0)
        every = renderer.render(scene, "wedges", intensity=intensity, tile_cull=False, subsample=0.0)
        entries = 4 * every.stats["binned_wedge_tiles"]
        assert every.stats["wedge_tiles_kept"] <= entries
        assert culled.stats["wedge_tiles_kept"] <= 2 / 3 * every.stats["wedge_tiles_kept"], (scene.meshes[-1].name, culled.stats, entries)
        np.testing.assert_allclose(culled.visibility, every.visibility, rtol=0, atol=1e-5)


# subsample (issue 30) against every pixel computed, built-in scenes at
# 128x128 under a light of radius 1 (measured: largest difference 0.0054 on
# the sphere (RMSE over the penumbra 0.00008), 0.0042 on the cube
# (0.00015), 0 on the box resting on the floor; at the scenes' own radii 0
# on all but the overlapping casters). Where the two casters' penumbrae
# overlap it was 0.027 (0.0013) until map_solids (issue 28): the rays the
# solid layers hide (the box under the sphere) are hidden in one pixel and
# not the next (the march's points, the layers' texels), a step that the
# interpolation spreads: 0.108 at one pixel (0.0040; 0.034 at the scene's
# own radius), while both images are 0.0363 from the exact visibility
# (`triangle_masks`, 1024 samples; 0.0606 without map_solids). Refusing to
# interpolate from pixels where the map bound moved v keeps 0.033, at 1.52x
# and 1.19x wedges' time on generated:1 and 38 at 256x256 (a build not
# committed, timed against this one with benchmarks/ab_render_time.py). Bounds:
# about twice those; and subsample's error against the exact visibility
# within 0.001 of every pixel's.
SUBSAMPLE_BOUNDS = {"sphere_on_plane": (0.01, 0.0002), "cube_on_plane": (0.01, 0.0003), "overlapping_casters": (0.2, 0.008), "resting_box": (1e-6, 1e-6)}


@pytest.mark.parametrize("name", list(SUBSAMPLE_BOUNDS))
def test_subsample_interpolates_where_the_penumbra_is_smooth(renderer: penumbra.Renderer, name: str) -> None:
    """subsample (the default, 0.1 light radii) computes the pixels with
    even x and y and interpolates most others, and the image stays that of
    every pixel computed to within the measured bounds; the resting box's
    contact, where an edge touches the floor, is computed pixel by pixel
    (no difference at all). subsample=0 and the 2002 interpolation
    interpolate nothing."""
    from penumbra import scenes

    scene = scenes.get(name, width=128, height=128, light_radius=1.0)
    sub = renderer.render(scene, "wedges")
    every = renderer.render(scene, "wedges", subsample=0.0)
    assert every.stats["interpolated_pixels"] == 0
    # Three quarters of the pixels are off the coarse grid, and those of
    # tiles without wedges are evaluated at once (their map read alone):
    # measured 4,019-6,962 interpolated of 16,384.
    assert sub.stats["interpolated_pixels"] > 0.2 * 128 * 128, sub.stats
    largest, rms = SUBSAMPLE_BOUNDS[name]
    d = sub.visibility - every.visibility
    v = every.visibility
    band = (v > 0.02) & (v < 0.98)
    assert np.abs(d).max() <= largest, (np.abs(d).max(), largest)
    assert np.sqrt(np.mean(d[band] ** 2)) <= rms
    exact = renderer.render(scene, "triangle_masks", n_samples=1024).visibility
    region = (exact > 0.02) & (exact < 0.98)
    error = {name: float(np.sqrt(np.mean((image - exact)[region] ** 2))) for name, image in (("sub", sub.visibility), ("every", every.visibility))}
    assert error["sub"] <= error["every"] + 0.001, error
    old = renderer.render(scene, "wedges", intensity="interpolation", subsample=0.5)
    assert old.stats["interpolated_pixels"] == 0


def test_subsample_keeps_narrow_penumbrae_computed(renderer: penumbra.Renderer) -> None:
    """Under a small light the edges' projections move fast across the
    pixels, so kappa times the pixels' spacing exceeds the bound inside
    every wedge: no pixel inside a wedge is interpolated, and the image is
    that of every pixel computed (only lit and umbra pixels, where no edge
    can reach the disk, take their neighbours' value)."""
    scene = long_edge_scene(0.02)
    sub = renderer.render(scene, "wedges")
    every = renderer.render(scene, "wedges", subsample=0.0)
    np.testing.assert_array_equal(sub.visibility, every.visibility)


@pytest.mark.parametrize("size", [(1, 1), (3, 1), (1, 7), (9, 17), (33, 5)])
def test_subsample_handles_images_smaller_than_its_grids(renderer: penumbra.Renderer, size: tuple[int, int]) -> None:
    """Images narrower than the cascade's grids (4 pixels) or of odd size:
    pixels whose neighbours fall outside the image are evaluated, and the
    image is the one of every pixel computed (measured: identical)."""
    from penumbra import scenes

    scene = scenes.get("overlapping_casters", width=size[0], height=size[1], light_radius=1.0)
    sub = renderer.render(scene, "wedges").visibility
    every = renderer.render(scene, "wedges", subsample=0.0).visibility
    assert sub.shape == (size[1], size[0]) and np.isfinite(sub).all()
    np.testing.assert_allclose(sub, every, rtol=0, atol=1e-6)


def test_subsample_moves_no_pixel_far_on_generated_scenes(renderer: penumbra.Renderer) -> None:
    """On the 40 generated scenes at 96x96, subsample moves no pixel by
    more than 0.3 from every pixel computed (measured: 0.234 at most, seed
    38; 0.161 before map_solids, whose rays hidden in one pixel and not the
    next the interpolation spreads: see SUBSAMPLE_BOUNDS), and its penumbra
    RMSE against the truth is within 0.001 of every pixel's (measured: at
    most 5e-5 above it). Without the check that neighbours differ by no
    more than the shift bound allows, the mean spread the gate's and the
    rays' stray pixels: 0.546 on seed 1, 0.460 on seed 20 (a build without it)."""
    from penumbra import metrics, scenes

    if scenes.meshes_folder() is None:
        pytest.skip("the shared meshes are absent")
    truth = pytest.importorskip("penumbra.mitsuba")
    pytest.importorskip("mitsuba")
    for seed in range(40):
        scene = scenes.generate(seed, width=96)
        sub = renderer.render(scene, "wedges").visibility
        every = renderer.render(scene, "wedges", subsample=0.0).visibility
        assert np.abs(sub - every).max() <= 0.3, (seed, float(np.abs(sub - every).max()))
        # The generated suite's truth (tests/test_generated_scenes.py's, cached).
        gt = truth.ground_truth(scene, spp=256, kinds=["visibility"]).visibility
        region = metrics.penumbra_region(gt)
        assert metrics.rmse(sub, gt, region) <= metrics.rmse(every, gt, region) + 0.001, seed


def test_degenerate_silhouettes_stay_finite_and_in_0_1(renderer: penumbra.Renderer) -> None:
    """Collinear edges, a vertical edge under the light, junction vertices
    and a 0.1-radian spike (the degenerate suite's scenes) with lights from tiny to wider than the casters, with and without
    extra wedges and with the paper's construction: finite, in [0, 1], and
    the stats name the degeneracy."""
    for case, (build, _) in CASES.items():
        base = build()
        for radius in (1e-4, 0.4, 1.5):
            light = penumbra.SphereLight(base.light.center, radius, intensity=40.0)
            s = base.with_light(light)
            for params in ({}, INTERPOLATION | {"acute_wedges": 8}, INTERPOLATION, {"repairs": "none"}, {"hard_term": "lit_side"}, {"overlap": "sum"}):
                result = renderer.render(s, "wedges", **FAST["wedges"], **params)
                check_images(result, f"{case} r={radius} {params}")
                if case == "vertex_with_four_silhouette_edges" and radius == 0.4:
                    assert result.stats["silhouette_junction_vertices"] >= 1, result.stats
                if case == "acute_corner" and radius == 0.4 and params.get("acute_wedges"):
                    assert result.stats["extra_wedges"] > 0, result.stats


def test_open_and_non_manifold_casters_get_pvms_decision(renderer: penumbra.Renderer) -> None:
    """The silhouettes are pvm's: the same edges of open and non-manifold
    casters (open_edges="silhouette"), the same refusal with "error"."""
    base = penumbra.scenes.get(width=48, height=48)
    bar, fin = finned_box()
    clean = penumbra.Scene([ground_slab(), bar], base.light, base.camera)
    finned = penumbra.Scene([ground_slab(), fin], base.light, base.camera)
    for s in (clean, finned):
        assert renderer.render(s, "wedges").stats["silhouette_edges"] == renderer.render(s, "pvm").stats["silhouette_edges"]
    with pytest.raises(penumbra.MeshError, match=r"mesh 'finned'.*not a 2-manifold"):
        renderer.render(finned, "wedges", open_edges="error")
    # The fin lies inside the box, its open edges hidden from the light's centre: the same shadow.
    np.testing.assert_array_equal(renderer.render(finned, "wedges").visibility, renderer.render(clean, "wedges").visibility)

    open_scene = penumbra.Scene([ground_plane(), sphere((0.0, 1.6, 0.0), 1.0)], base.light, base.camera)
    with pytest.raises(penumbra.MeshError, match=r"mesh 'ground'.*boundary edges"):
        renderer.render(open_scene, "wedges", open_edges="error")
    assert renderer.render(open_scene, "wedges").stats["silhouette_edges"] == renderer.render(open_scene, "pvm").stats["silhouette_edges"]


def test_parameters_are_checked(renderer: penumbra.Renderer) -> None:
    scene = penumbra.scenes.get(width=16, height=16)
    with pytest.raises(penumbra.ParameterError, match="acute_wedges"):
        renderer.render(scene, "wedges", acute_wedges=-1)
    with pytest.raises(penumbra.ParameterError, match="hard_term"):
        renderer.render(scene, "wedges", hard_term="nowhere")
    with pytest.raises(penumbra.ParameterError, match="repairs"):
        renderer.render(scene, "wedges", repairs="centre")
    with pytest.raises(penumbra.ParameterError, match="intensity"):
        renderer.render(scene, "wedges", intensity="sampled")
    with pytest.raises(penumbra.ParameterError, match="overlap"):
        renderer.render(scene, "wedges", overlap="max")
    params = renderer.render(scene, "wedges").params
    assert (params["acute_wedges"], params["falloff"], params["hard_term"], params["repairs"]) == (0, False, "at_point", "all")
    assert (params["intensity"], params["overlap"]) == ("coverage", "gate")


def test_wedges_beat_hard_against_ground_truth_on_every_builtin_scene(renderer: penumbra.Renderer, tmp_path_factory: pytest.TempPathFactory) -> None:
    from penumbra import metrics

    for name, errors, result, gt in builtin_scenes_against_truth(renderer, tmp_path_factory.mktemp("gt"), 96, {"wedges": {"method": "wedges"}}):
        hard, wedges = errors["hard"], errors["wedges"]
        # Measured at 96x96: wedges' penumbra RMSE is 0.15-0.46 of hard's.
        assert wedges["visibility_rmse_penumbra"] < 0.55 * hard["visibility_rmse_penumbra"], (name, wedges, hard)
        stray, out_of = metrics.stray_pixels(result.visibility, gt.visibility)
        assert stray <= 0.002 * out_of, (name, stray, out_of)


@pytest.mark.parametrize("scale", [1e-3, 1e10, 1e17])
def test_visibility_does_not_depend_on_the_scene_scale(renderer: penumbra.Renderer, scale: float) -> None:
    """Planes are unit normals through edge points and every distance a
    difference of nearby points: measured at most 3e-4 off at every scale
    here (lit_side at 1e17; 2e-5 with the defaults)."""
    from test_pvm import scaled_scene

    base = penumbra.scenes.get("sphere_on_plane", width=64, height=64)
    for params in ({}, {"hard_term": "lit_side"}):
        expected = renderer.render(base, "wedges", **params).visibility
        got = renderer.render(scaled_scene(base, scale), "wedges", **params).visibility
        np.testing.assert_allclose(got, expected, atol=2e-3)


def test_extra_wedges_at_an_acute_tip_bring_it_closer_to_ground_truth(renderer: penumbra.Renderer, tmp_path_factory: pytest.TempPathFactory) -> None:
    """4.1, Figure 7, on `scenes.acute_caster` (a 23-degree tip): measured at
    96x96 (benchmarks/acute_wedges.toml has 128x128): acute_wedges=6 takes
    the penumbra RMSE from 0.073 to 0.055 (0.76 of it)."""
    pm = pytest.importorskip("penumbra.mitsuba", reason="Mitsuba 3 is not installed")
    from penumbra import metrics

    import trimesh

    scene = penumbra.scenes.get("acute_caster", width=96, height=96)
    caster = scene.meshes[1]
    assert trimesh.Trimesh(caster.vertices, caster.faces, process=False).volume > 0, "outward faces"
    gt = pm.ground_truth(scene, spp=256, cache_dir=tmp_path_factory.mktemp("gt"), kinds=("visibility",)).visibility
    region = metrics.penumbra_region(gt)
    plain = renderer.render(scene, "wedges", **INTERPOLATION)
    extra = renderer.render(scene, "wedges", **INTERPOLATION, acute_wedges=6)
    assert plain.stats["extra_wedges"] == 0 < extra.stats["extra_wedges"]
    e0 = metrics.rmse(plain.visibility, gt, region)
    e6 = metrics.rmse(extra.visibility, gt, region)
    assert e6 < 0.85 * e0, (e0, e6)


# Penumbra RMSE on the real-mesh suite of tests/test_real_meshes.py (160 x
# 160, ground truth at 1024 samples), measured on this branch; each test
# allows it 15% and 0.005 more, as that suite does. Stray pixels: at most
# 0.44% measured (cube close r=0.8 with the interpolation: the corners'
# cone side lines), else under 0.03%; bound 1%.
WEDGES_MEASURED: dict[str, dict[str, float]] = {
    # "defaults" (coverage, overlap=gate and the map bound with 32 rays; no
    # stray pixel) measured the same way for issue 28's map bound: without
    # the bound (map_samples=0) 0.0024, 0.0404, 0.0029, 0.0917, 0.0951,
    # 0.0838, 0.0480, 0.0672, 0.0180 in this order; with 16 rays (the
    # default before 32) 0.0027, 0.0395, 0.0029, 0.0598, 0.0598, 0.0685,
    # 0.0208, 0.0615, 0.0180 (32 rays raise the cube by up to 0.0009). "interpolation" and "falloff" are the values of the
    # earlier defaults (the 2002 interpolation, overlap=sum, no map bound).
    "cube.obj close r=0.3": {"defaults": 0.0036, "interpolation": 0.0326, "falloff": 0.0261},
    "cube.obj close r=0.8": {"defaults": 0.0376, "interpolation": 0.0823, "falloff": 0.0805},
    "cube.obj wide_floor r=0.3": {"defaults": 0.0037, "interpolation": 0.0568, "falloff": 0.0438},
    "spot.obj close r=0.3": {"defaults": 0.0497, "interpolation": 0.1630, "falloff": 0.1249},
    "spot.obj close r=0.8": {"defaults": 0.0501, "interpolation": 0.2144, "falloff": 0.1615},
    "spot.obj wide_floor r=0.3": {"defaults": 0.0638, "interpolation": 0.1764, "falloff": 0.1354},
    "teapot-mcguire-closed.obj close r=0.3": {"defaults": 0.0190, "interpolation": 0.0811, "falloff": 0.0663},
    "teapot-mcguire-closed.obj close r=0.8": {"defaults": 0.0609, "interpolation": 0.1498, "falloff": 0.1163},
    "teapot-mcguire-closed.obj wide_floor r=0.3": {"defaults": 0.0170, "interpolation": 0.1139, "falloff": 0.0817},
}
WEDGES_CONFIGS: dict[str, dict[str, object]] = {"defaults": {}, "interpolation": INTERPOLATION, "falloff": INTERPOLATION | {"falloff": True}}


@pytest.mark.parametrize("config", list(WEDGES_CONFIGS))
@pytest.mark.parametrize("name", list(WEDGES_MEASURED))
def test_wedges_hold_their_measured_accuracy_on_real_meshes(renderer: penumbra.Renderer, truth: dict[str, np.ndarray], name: str, config: str) -> None:
    if name not in SUITE:
        pytest.skip("the shared meshes are absent")
    scene = SUITE[name]
    gt = truth_of(truth, name, scene)
    bounds = {"rmse": 1.15 * WEDGES_MEASURED[name][config] + 0.005, "stray_percent": 1.0}
    check_against_truth(f"{name} wedges {config}", renderer.render(scene, "wedges", **WEDGES_CONFIGS[config]), gt, bounds)


# Issue 28, seeds 0-11 of the generated scenes at 96x96 (Mitsuba at 256
# samples), measured over seeds 0-11 (the rows of `penumbra bench --config benchmarks/generated.toml`): the
# defaults' penumbra RMSE is 0.27-0.94 of hard's on every scene (0.94: seed
# 1, a boot as wide as a third of its distance to the light; 0.35: seed 11,
# the boot between the light and spot that the 2002 interpolation got
# wrong over nearly the whole floor at 2.2x hard's error), median 0.136;
# stray pixels at most 1.17% (seed 1). Bounds: no scene above hard, the
# median below 0.16, stray below 1.5%.
GENERATED_SEEDS = range(12)


def test_wedges_beat_hard_on_generated_scenes(renderer: penumbra.Renderer, tmp_path_factory: pytest.TempPathFactory) -> None:
    pm = pytest.importorskip("penumbra.mitsuba", reason="Mitsuba 3 is not installed")
    from penumbra import metrics, scenes

    if scenes.meshes_folder() is None:
        pytest.skip("the shared meshes are absent")
    from test_real_meshes import ARTIFACTS, leave_images

    errors = []
    for seed in GENERATED_SEEDS:
        scene = scenes.generate(seed, width=96)
        truth_result = pm.ground_truth(scene, spp=256)
        gt = truth_result.images["visibility"]
        hard = metrics.compare_images(renderer.render(scene, "hard").visibility, truth_result)["visibility_rmse_penumbra"]
        result = renderer.render(scene, "wedges")
        e = metrics.compare_images(result.visibility, truth_result)["visibility_rmse_penumbra"]
        stray, out_of = metrics.stray_pixels(result.visibility, gt)
        if not (e <= hard and stray <= 0.015 * out_of):
            folder = leave_images(f"generated {seed} wedges", result.visibility, gt, ARTIFACTS)
            pytest.fail(f"{scene.name}: wedges {e:.3f} against hard {hard:.3f}, {stray} of {out_of} stray; images in {folder}")
        errors.append(e)
    assert float(np.median(errors)) < 0.16, errors

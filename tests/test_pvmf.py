"""Penumbra volume mask filtering (issue 5, Cournia chapter 5)."""

from __future__ import annotations

import numpy as np
import pytest

import penumbra
from penumbra.comparison import PAPER
from penumbra import scenes
from penumbra.scenes import box, ground_plane, ground_slab
from stress_scenes import builtin_scenes_against_truth, seeded_renders

# The paper's settings where pvmf's defaults depart from them (the square
# kernel, the 12-pixel blur, unit offsets, the umbra filtered, s_e 0.5, the
# mask at the map's size).
PVMF_PAPER = PAPER["pvmf"]

RADII = [0.0, 1e-4, 0.05, 0.5, 2.2]


def penumbra_pixels(result: penumbra.RenderResult, object_id: int = 0) -> np.ndarray:
    v = result.visibility
    return (v > 0.02) & (v < 0.98) & (result.object_id == object_id)


def world_gradient(result: penumbra.RenderResult) -> np.ndarray:
    """|grad v| per world unit along the image rows and columns (NaN where a
    neighbour lies on another object), so 1/|grad v| is a local penumbra width."""
    v, p, ids = result.visibility, result.position, result.object_id
    out = np.full(v.shape, np.nan)
    for axis in (0, 1):
        dv = np.abs(np.diff(v, axis=axis))
        dp = np.linalg.norm(np.diff(p, axis=axis), axis=-1)
        same = np.diff(ids, axis=axis) == 0
        g = np.where(same & (dp > 0), dv / np.where(dp > 0, dp, 1), np.nan)
        pad = [(0, 1), (0, 0)] if axis == 0 else [(0, 0), (0, 1)]
        out = np.fmax(out, np.pad(g, pad, constant_values=np.nan))
    return out


def test_every_scene_renders_with_its_passes_stats_and_intermediates(renderer: penumbra.Renderer) -> None:
    moved = 0
    for name in penumbra.scenes.names():
        scene = penumbra.scenes.get(name, width=64, height=64)
        renderer.clear_pass_cache()  # every pass runs, and is timed
        # The paper's settings, whose blur pass the defaults skip (n_blur 0).
        result = renderer.render(scene, "pvmf", intermediates=True, map_size=512, **PVMF_PAPER)
        assert list(result.timings) == ["gbuffer", "shadow_map", "mask", "object_map", "estimation", "blur", "shading", "readback"]
        for key in ("pvmf_mask_depth", "pvmf_edge_distance", "pvmf_visibility_raw", "pvmf_blur_mask", "pvmf_filter_width", "shadow_map"):
            assert key in result.images, key
            assert np.isfinite(result.images[key]).all(), key
        assert result.images["pvmf_edge_distance"].shape == (512, 512)
        s = result.stats
        assert s["mask_quads"] == 2 * (s["silhouette_edges"] - s["light_parallel_edges"] - s["hidden_silhouette_edges"]) > 0
        # Filtered: masked pixels plus those failing the test outside every volume (5.2).
        # The blur takes the filtered pixels whose filter spans a texel at least (blur_min_width).
        assert 0 < s["masked_pixels"] <= s["filtered_pixels"]
        assert 0 < s["blurred_pixels"] == int(result["pvmf_blur_mask"].sum()) <= s["filtered_pixels"]
        # The paper's filter alone: no map bound, no solid layers read.
        assert s["map_bounded_pixels"] == s["map_raised_pixels"] == 0 and "solid_meshes" not in s
        # The defaults' bound moves filtered pixels, each one way, none on
        # some scenes (the sphere's shadow is the filter's already).
        d = renderer.render(scene, "pvmf", map_size=512).stats
        assert d["solid_meshes"] >= 1 and d["map_bounded_pixels"] + d["map_raised_pixels"] <= d["filtered_pixels"], d
        moved += d["map_bounded_pixels"] + d["map_raised_pixels"]
        assert ((result.visibility >= 0) & (result.visibility <= 1)).all()
        # Stored d_e is the light-to-edge distance: beyond the light's radius.
        d_e = result["pvmf_edge_distance"]
        assert (d_e[d_e > 0] > scene.light.radius).all()
    assert moved > 0


@pytest.mark.parametrize("name", penumbra.scenes.names())
def test_no_nan_from_radius_zero_to_larger_than_the_casters(renderer: penumbra.Renderer, name: str) -> None:
    for radius in RADII:
        scene = penumbra.scenes.get(name, width=48, height=48, light_radius=radius)
        for params in ({}, {**PVMF_PAPER, "bias": "midpoint"}):
            result = renderer.render(scene, "pvmf", intermediates=True, map_size=512, **params)
            for key, image in result.images.items():
                assert np.isfinite(image).all(), (radius, key, params)
            assert result.visibility.min() >= 0 and result.visibility.max() <= 1


@pytest.mark.parametrize("bias", ["second_depth", "slope", "midpoint"])
def test_radius_zero_is_the_hard_shadow_with_no_work(renderer: penumbra.Renderer, bias: str) -> None:
    scene = penumbra.scenes.get("overlapping_casters", width=96, height=96, light_radius=0.0)
    result = renderer.render(scene, "pvmf", bias=bias)
    np.testing.assert_array_equal(result.visibility, renderer.render(scene, "hard", bias=bias).visibility)
    assert result.stats["mask_quads"] == result.stats["filtered_pixels"] == result.stats["blurred_pixels"] == 0
    assert "blur" not in result.timings


def test_n_blur_zero_leaves_the_raw_estimate(renderer: penumbra.Renderer) -> None:
    scene = penumbra.scenes.get("cube_on_plane", width=96, height=96)
    raw = renderer.render(scene, "pvmf", n_blur=0, intermediates=True)
    blurred = renderer.render(scene, "pvmf", n_blur=12, intermediates=True)
    assert "blur" not in raw.timings and raw.stats["blurred_pixels"] == 0
    np.testing.assert_array_equal(raw.visibility, raw["pvmf_visibility_raw"])
    # The blur changes only the estimate's masked pixels, and it changes them.
    np.testing.assert_array_equal(blurred["pvmf_visibility_raw"], raw.visibility)
    outside = blurred["pvmf_blur_mask"] == 0
    np.testing.assert_array_equal(blurred.visibility[outside], raw.visibility[outside])
    assert np.abs(blurred.visibility - raw.visibility)[~outside].max() > 0.05


def id_aware_blur(v: np.ndarray, mask: np.ndarray, ids: np.ndarray, n_blur: int) -> np.ndarray:
    """Cournia 5.3 in numpy: per axis, the mean of the same-object texels
    within n_blur / 2, only where the mask is set."""
    half = n_blur // 2
    for axis in (1, 0):
        out = v.copy()
        for y, x in zip(*np.nonzero(mask)):
            line = v[y, :] if axis == 1 else v[:, x]
            line_ids = ids[y, :] if axis == 1 else ids[:, x]
            c = x if axis == 1 else y
            lo, hi = max(c - half, 0), min(c + half + 1, len(line))
            same = line_ids[lo:hi] == ids[y, x]
            out[y, x] = line[lo:hi][same].mean()
        v = out
    return v


def test_blur_is_separable_and_never_mixes_objects(renderer: penumbra.Renderer) -> None:
    # The box's shadow falls at its own base: blurring across the object
    # boundary would pull lit box values into the shadowed ground (5.3, B).
    scene = penumbra.scenes.get("resting_box", width=64, height=64)
    result = renderer.render(scene, "pvmf", n_blur=10, intermediates=True)
    raw, mask, ids = result["pvmf_visibility_raw"], result["pvmf_blur_mask"] > 0, result.object_id
    expected = id_aware_blur(raw.astype(np.float64), mask, ids, 10)
    np.testing.assert_allclose(result.visibility, expected, atol=1e-5)
    # Ignoring the ids would give a different image here.
    mixed = id_aware_blur(raw.astype(np.float64), mask, np.zeros_like(ids), 10)
    assert np.abs(mixed - expected).max() > 0.1


def test_seed_fixes_the_jitter(renderer: penumbra.Renderer) -> None:
    scene = penumbra.scenes.get("sphere_on_plane", width=64, height=64)
    a, c = seeded_renders(renderer, scene, "pvmf", n_blur=0)
    assert np.abs(a.visibility - c.visibility).max() > 0.01


def test_penumbra_and_cost_grow_with_the_light_radius(renderer: penumbra.Renderer) -> None:
    counts, filtered = [], []
    for radius in (0.1, 0.4, 1.2):
        scene = penumbra.scenes.get("cube_on_plane", width=96, height=96, light_radius=radius)
        result = renderer.render(scene, "pvmf", offsets="radius", umbra="skip")
        counts.append(int(penumbra_pixels(result).sum()))
        filtered.append(result.stats["filtered_pixels"])
    assert counts[0] < counts[1] < counts[2], counts
    assert filtered[0] < filtered[1] < filtered[2], filtered


def ground_penumbra_widths(result: penumbra.RenderResult) -> tuple[float, float]:
    """Median penumbra width (1 / |grad v|, world units) on the ground near
    the resting box's base and far from it (horizontal distance from the
    box's axis below 0.9 and within 1.6-2.5; the box is 0.8 wide)."""
    g = world_gradient(result)
    ground = penumbra_pixels(result) & np.isfinite(g)
    reach = np.linalg.norm(result.position[..., [0, 2]], axis=-1)
    near, far = ground & (reach < 0.9), ground & (reach > 1.6) & (reach < 2.5)
    assert near.sum() > 20 and far.sum() > 20, (near.sum(), far.sum())
    return float(1 / np.median(g[near])), float(1 / np.median(g[far]))


def test_contact_hardening_on_the_resting_box(renderer: penumbra.Renderer) -> None:
    # The box stands on the ground: the true shadow is sharp where it meets
    # the ground and widens with the height of the occluding edge above it.
    scene = penumbra.scenes.get("resting_box", width=160, height=160)
    near_ref, far_ref = ground_penumbra_widths(renderer.render(scene, "reference", n_samples=256))
    # Measured 0.42 near against 1.14 far.
    assert near_ref < 0.5 * far_ref, (near_ref, far_ref)
    # With the paper's settings PVMF hardens far less: its 13-pixel blur and
    # unit-offset volumes widen everything (measured 1.6 near against 2.5 far;
    # 0.64 against 1.25 with n_blur = 0).
    for params in (PVMF_PAPER, {**PVMF_PAPER, "n_blur": 0}):
        near, far = ground_penumbra_widths(renderer.render(scene, "pvmf", **params))
        assert near < 0.8 * far, (params, near, far)
    # With its defaults it follows the reference: measured 0.38
    # near against 0.98 far. Repair "distance" (the mask's edge distance is
    # that of the part of the edge a volume comes from, not the nearer end's:
    # the box's vertical edges reach from the ground to its top) is what
    # makes the near penumbra narrow: 0.56 against 1.20 without it.
    near, far = ground_penumbra_widths(renderer.render(scene, "pvmf"))
    assert near < 0.5 * far and 0.5 * near_ref < near < 1.5 * near_ref and 0.7 * far_ref < far < 1.3 * far_ref, (near, far)
    # (Measured with 5.2's d_o, the mask's, and the filter alone:
    # occluder_distance="darker", the default, narrows the near penumbra
    # without the repair too, 0.47, and so does the map bound, map_samples,
    # the default since issue 28: 0.41 against 0.47 without the repair.)
    near, _ = ground_penumbra_widths(renderer.render(scene, "pvmf", occluder_distance="nearest_volume", map_samples=0))
    near_without, _ = ground_penumbra_widths(renderer.render(scene, "pvmf", repairs="hidden+horizon", occluder_distance="nearest_volume", map_samples=0))
    assert near < 0.8 * near_without, (near, near_without)


def test_pvmf_beats_hard_against_ground_truth_on_every_builtin_scene(renderer: penumbra.Renderer, tmp_path_factory: pytest.TempPathFactory) -> None:
    settings = {"paper": {"method": "pvmf", **PVMF_PAPER}, "best": {"method": "pvmf", **PVMF_PAPER, "kernel": "disk", "n_blur": 0}, "defaults": {"method": "pvmf"}}
    for name, errors, _, _ in builtin_scenes_against_truth(renderer, tmp_path_factory.mktemp("gt"), 128, settings):
        hard, paper, best, defaults = (errors[k]["visibility_rmse_penumbra"] for k in ("hard", "paper", "best", "defaults"))
        print(name, {"hard": hard, "paper": paper, "best": best, "defaults": defaults})
        # Measured at 128x128 (hard: 0.27 everywhere; `pytest -s` prints
        # them): the paper's settings reach 0.46-0.69 of hard's penumbra RMSE
        # (its 13-pixel blur is wide against these penumbrae), a disk kernel
        # without blur 0.11-0.25, the defaults 0.11-0.24.
        assert paper < 0.85 * hard, (name, paper, hard)
        assert best < 0.6 * hard, (name, best, hard)
        assert defaults < 0.6 * hard, (name, defaults, hard)


def test_open_casters_render_and_open_edges_error_refuses_them(renderer: penumbra.Renderer) -> None:
    base = penumbra.scenes.get(width=48, height=48)
    scene = penumbra.Scene([ground_plane(), base.meshes[1]], base.light, base.camera)
    with pytest.raises(penumbra.MeshError, match=r"mesh 'ground'.*boundary edges"):
        renderer.render(scene, "pvmf", open_edges="error")
    assert np.isfinite(renderer.render(scene, "pvmf").visibility).all()


def test_pvmf_parameters_are_checked(renderer: penumbra.Renderer) -> None:
    scene = penumbra.scenes.get(width=16, height=16)
    for bad, match in [
        ({"s_e": 0.0}, r"s_e.*\(0, 1\]"),
        ({"s_e": 1.5}, "s_e"),
        ({"s_p": -1.0}, "s_p"),
        ({"n_pcf": 0}, "n_pcf"),
        ({"n_pcf": 2.5}, "n_pcf.*integer"),
        ({"n_blur": -2}, "n_blur"),
        ({"seed": -1}, "seed"),
        ({"kernel": "gauss"}, "kernel"),
        ({"offsets": "huge"}, "offsets"),
        ({"umbra": "maybe"}, "umbra"),
        ({"filter": "cubic"}, "filter"),
        ({"bias": "third_depth"}, "bias"),
        ({"falloff": True}, "unknown parameter"),
        ({"estimate": "exact"}, "estimate"),
        ({"estimate": "area", "kernel": "square"}, "kernel='square' does not apply"),
        ({"occluder_distance": "mean"}, "occluder_distance"),
    ]:
        with pytest.raises(penumbra.ParameterError, match=match):
            renderer.render(scene, "pvmf", **bad)
    params = renderer.render(scene, "pvmf").params
    assert params["bias"] == "slope" and params["n_pcf"] == 7 and params["n_blur"] == 0
    assert (params["kernel"], params["offsets"], params["umbra"], params["s_e"]) == ("disk", "radius", "skip", 0.02)
    assert params["occluder_distance"] == "darker"


def test_one_caster_gives_the_same_image_whatever_the_occluder_distance(renderer: penumbra.Renderer) -> None:
    """occluder_distance: where every volume covering a texel comes from
    edges at one distance (a sphere's silhouette, seen from its light), the
    farthest enclosing edge is the nearest volume's, and the occluder on a
    shadowed receiver's centre ray (the sphere's lit cap) lies nearer the
    light than them, so the options change (almost) nothing. Only
    "farthest_edge" draws the second mask pass."""
    scene = penumbra.scenes.get("sphere_on_plane", width=64, height=64)
    base = renderer.render(scene, "pvmf", occluder_distance="nearest_volume")
    assert "mask_farthest" not in base.timings
    for choice in ("farthest_edge", "darker"):
        other = renderer.render(scene, "pvmf", occluder_distance=choice, intermediates=True)
        assert ("mask_farthest" in other.timings) == (choice == "farthest_edge")
        off = np.abs(other.visibility - base.visibility) > 0.05
        assert off.mean() < 0.01, f"{choice}: {off.mean():.2%} of pixels moved by more than 0.05"


@pytest.mark.parametrize("thickness", [1e-4, 1e-3])
def test_thin_closed_casters_do_not_shadow_their_lit_face(renderer: penumbra.Renderer, thickness: float) -> None:
    """Issue 22, item 2: a closed plate thinner than the depth a map texel
    spans along its slope has its back faces (the second-depth map) within
    that depth of its lit top, which then shadowed itself: visibility
    0.57-0.75 on the top of a 1e-4 plate under pvmf's former default,
    `second_depth` (`benchmarks/point_light.py` counts it for `hard`: 548-1011
    acne pixels). pvmf now defaults to `slope`, as `hard` does: the top is
    lit, with a point light and with an area light."""
    base = penumbra.scenes.get(width=96, height=96)
    plate = box((0.0, 0.5, 0.0), (2.0, thickness, 2.0), name="plate")
    for radius in (0.0, 0.5):
        scene = penumbra.Scene([ground_slab(), plate], base.light.with_radius(radius), base.camera)
        for method, params in (("pvmf", {}), ("pvmf", PVMF_PAPER), ("hard", {})):
            for map_size in (256, 2048):
                result = renderer.render(scene, method, map_size=map_size, **params)
                top = (result.object_id == 1) & (result.normal[..., 1] > 0.99)
                assert top.sum() > 250
                # Measured: 1 on every top pixel.
                assert result.visibility[top].min() == 1.0, (method, params, map_size, radius, result.visibility[top].mean())
    # The scheme itself still assumes casters thicker than that (README, bias study).
    scene = penumbra.Scene([ground_slab(), plate], base.light.with_radius(0.0), base.camera)
    result = renderer.render(scene, "hard", map_size=256, bias="second_depth")
    top = (result.object_id == 1) & (result.normal[..., 1] > 0.99)
    assert result.visibility[top].mean() < 0.9 if thickness < 1e-3 else result.visibility[top].mean() <= 1.0


@pytest.mark.parametrize("name", ["sphere_on_plane", "cube_on_plane", "overlapping_casters"])
def test_defaults_converge_to_hard_as_the_light_shrinks(renderer: penumbra.Renderer, name: str) -> None:
    """pvmf tends to `hard` as the radius goes to 0, with its defaults (no
    blur) and with the paper's settings (n_blur 12): the blur (5.3) takes
    only pixels whose filter is at least `blur_min_width` texels wide, and
    w_pcf shrinks with the radius. The paper's blur of every filtered pixel
    (blur_min_width=0) kept 0.8-1.0% of these scenes' pixels off hard by
    more than 0.5 at r = 1e-5 (measured at 96x96); with the default, none."""
    scene = penumbra.scenes.get(name, width=96, height=96, light_radius=1e-5)
    hard = renderer.render(scene, "hard").visibility
    mismatch = lambda **p: float((np.abs(renderer.render(scene, "pvmf", **p).visibility - hard) > 0.5).mean())  # noqa: E731
    assert mismatch() <= 0.001
    assert mismatch(**PVMF_PAPER) <= 0.001
    assert mismatch(**PVMF_PAPER, blur_min_width=0.0) >= 0.005


def test_the_area_estimate_keeps_the_umbra_of_a_caster_under_another(renderer: penumbra.Renderer) -> None:
    """A plate near the light whose penumbra volumes cover the shadow of a box
    resting on the floor: every pixel there takes d_o from the plate's edges,
    so 5.2's filter (estimate="pcf") spans the light's projection through the
    plate, far wider than the box's, and counts the box's failing taps as a
    small fraction of it: the box's umbra comes out lit (measured: mean error
    0.70 there against `reference` at 256 samples, penumbra RMSE 0.081;
    `hard` 0.255). estimate="area" weighs each failing tap by the part of the
    light its occluder hides, within that occluder's own light cone: 0.138
    and 0.059. (Before the floor slab was left out of the shadow map,
    casters.rs, its own texels failed wide filters' taps too: the penumbra
    RMSE was 0.146 with "pcf" and 0.067 with "area".)"""
    base = penumbra.scenes.get("resting_box", width=96, height=96)
    light = base.light.with_radius(0.5)
    centre = np.asarray(light.center)
    plate = box(tuple(centre + 0.25 * (np.array([1.0, 0.0, -2.0]) - centre)), (0.6, 0.05, 0.6), object_id=2, name="plate")
    low = box((0.0, 0.5, 0.0), (1.0, 1.0, 1.0), yaw_degrees=20.0)
    scene = penumbra.Scene([ground_slab(), low, plate], light, base.camera, name="plate over a box")
    truth = renderer.render(scene, "reference", n_samples=256).visibility
    umbra = (truth < 0.05) & (renderer.render(scene, "hard").object_id == 0)
    region = (truth > 0.02) & (truth < 0.98)
    assert umbra.sum() >= 15 and region.sum() > 300
    errors = {}
    # The filter alone (map_samples=0): the map bound, the default since
    # issue 28, darkens the box's umbra for "pcf" too (measured 0.0012 and
    # 0.057 with it).
    settings = {
        "pcf": {"estimate": "pcf", "occluder_distance": "nearest_volume", "map_samples": 0},
        "area": {"estimate": "area", "occluder_distance": "nearest_volume", "map_samples": 0},
        "darker": {},
    }
    for name, params in settings.items():
        v = renderer.render(scene, "pvmf", **params).visibility
        errors[name] = (float(np.abs(v - truth)[umbra].mean()), float(np.sqrt(((v - truth)[region] ** 2).mean())))
    assert errors["pcf"][0] > 0.5, errors
    assert errors["area"][0] < 0.3 and errors["area"][1] < errors["pcf"][1], errors
    # The default, occluder_distance="darker", filters the box's shadowed
    # receivers a second time for the box's own distance (the occluder on
    # their centre ray, beyond the plate's edges): measured 0.0012 and 0.067
    # (0.0012 and 0.056 with the map bound, the default since issue 28).
    assert errors["darker"][0] < 0.1 and errors["darker"][1] < errors["pcf"][1], errors


@pytest.mark.parametrize("seed", [1, 23, 27])
def test_the_automatic_mask_size_changes_the_image_little(renderer: penumbra.Renderer, seed: int) -> None:
    """mask_size="auto" (the default) renders the mask a texel per pixel
    instead of at the map's 2048: on the generated scenes whose mask cost
    most (issue 30: 8.7x `hard`'s time on seed 27), measured at 96x96: 0-0.054%
    of pixels moved by more than 0.1, the mean by at most 0.0014."""
    folder = scenes.meshes_folder()
    if folder is None:
        pytest.skip("the shared meshes (../shared/meshes or $PENUMBRA_MESHES) are absent")
    scene = scenes.generate(seed, width=96, folder=folder)
    auto = renderer.render(scene, "pvmf", outputs=["visibility"])
    full = renderer.render(scene, "pvmf", outputs=["visibility"], mask_size="map")
    assert full.stats["mask_size"] == full.stats["map_size"] == 2048
    assert auto.stats["mask_size"] <= 512, "a texel per pixel at 96x96"
    d = np.abs(auto.visibility - full.visibility)
    assert (d > 0.1).mean() <= 0.002 and d.mean() <= 0.003, ((d > 0.1).mean(), d.mean())


def test_the_automatic_mask_size_is_at_most_the_maps(renderer: penumbra.Renderer) -> None:
    scene = penumbra.scenes.get("sphere_on_plane")
    small = renderer.render(scene, "pvmf", outputs=["visibility"], map_size=256)
    assert small.stats["mask_size"] == 256
    large = renderer.render(scene, "pvmf", outputs=["visibility"], map_size=4096)
    assert large.stats["mask_size"] < 4096
    with pytest.raises(penumbra.ParameterError, match="mask_size"):
        renderer.render(scene, "pvmf", mask_size="half")

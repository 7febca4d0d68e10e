"""The generated real-mesh suite (issue 28): `penumbra.scenes.generate`
scenes from the shared meshes and their corpus, every soft method against
Mitsuba ground truth on each.

Each method's penumbra visibility RMSE and stray pixels are held to what was
measured on the suite (`python3 -m penumbra bench --config
benchmarks/generated.toml` prints the same table, with times), and the
targets of issue 28 that are not met yet are strict xfails: they start
failing, and so say so, the day a method meets them. When a bound fails the
method, truth and difference images of the method's worst scenes are left
under test-artifacts/generated/.

Skipped without the shared meshes or Mitsuba. The truth (256 samples per
pixel, 96x96) is cached like `penumbra compare`'s: about 60 s to render on 2
cores the first time."""

from __future__ import annotations

import json
import statistics
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import penumbra
from penumbra import metrics, scenes
from penumbra.comparison import PAPER
from test_real_meshes import leave_images

FOLDER = scenes.meshes_folder()
pytestmark = pytest.mark.skipif(FOLDER is None, reason="the shared meshes (../shared/meshes or $PENUMBRA_MESHES) are absent")
ARTIFACTS = Path(__file__).resolve().parents[1] / "test-artifacts" / "generated"

SEEDS = range(40)
SIZE = 96
SPP = 256
SLOW_SEEDS = range(40, 100)
SLOW_SIZE = 160
# (name, method, parameters) of every setting the suite measures.
SETTINGS: list[tuple[str, str, dict[str, Any]]] = [
    ("hard", "hard", {}),
    ("pcss", "pcss", {}),
    ("pcss plane", "pcss", {"blocker_test": "plane"}),
    ("pcss mean", "pcss", {"blocker_depth": "mean"}),
    ("pcss paper search", "pcss", {"search": "uniform", "blocker_test": "plane", "blocker_depth": "mean"}),
    ("pcss paper", "pcss", PAPER["pcss"]),
    ("pcss cone", "pcss", {"blocker_test": "cone"}),
    ("pcss area", "pcss", {"estimate": "area"}),
    ("backprojection", "backprojection", {}),
    ("pvm", "pvm", {}),
    ("pvm before solid", "pvm", {"map_bound": "both", "map_samples": 16}),
    ("pvm 16 rays", "pvm", {"map_samples": 16}),
    ("pvm two", "pvm", {"edges": "two"}),
    ("pvm no map bound", "pvm", {"map_samples": 0}),
    ("pvm upper bound", "pvm", {"map_bound": "upper"}),
    ("pvm no control", "pvm", {"map_control": False}),
    ("pvm paper", "pvm", PAPER["pvm"]),
    ("pvm one edge", "pvm", {"edges": "one", "volume_map_size": "map", "lookup": "texel", "umbra_test": "none", "map_samples": 0}),
    ("pvmf", "pvmf", {}),
    ("pvmf behind", "pvmf", {"blocker_test": "behind"}),
    ("pvmf paper", "pvmf", PAPER["pvmf"]),
    ("pvmf area", "pvmf", {"estimate": "area"}),
    ("pvmf farthest edge", "pvmf", {"occluder_distance": "farthest_edge"}),
    ("pvmf nearest volume", "pvmf", {"occluder_distance": "nearest_volume"}),
    ("wedges", "wedges", {}),
    ("wedges before solid", "wedges", {"map_bound": "both"}),
    ("wedges no map bound", "wedges", {"map_samples": 0}),
    ("wedges upper bound", "wedges", {"map_bound": "upper"}),
    ("wedges independent", "wedges", {"occluders": "independent"}),
    ("wedges no solids", "wedges", {"map_solids": False}),
    ("pvmf no map bound", "pvmf", {"map_samples": 0}),
    ("pvmf 32 rays", "pvmf", {"map_samples": 32}),
    ("pvmf no solids", "pvmf", {"map_solids": False}),
    ("pvmf nearest volume no map bound", "pvmf", {"occluder_distance": "nearest_volume", "map_samples": 0}),
    ("pvm no solids", "pvm", {"map_solids": False}),
]


def measure(seeds: range, size: int) -> dict[str, dict[int, dict[str, float]]]:
    """setting -> seed -> {rmse, stray, of the scene at `size`}; the images
    of every render kept in `IMAGES` for the failure reports."""
    pm = pytest.importorskip("penumbra.mitsuba")
    pytest.importorskip("mitsuba")
    renderer = penumbra.Renderer()
    out: dict[str, dict[int, dict[str, float]]] = {name: {} for name, _, _ in SETTINGS}
    for seed in seeds:
        scene = scenes.generate(seed, width=size, folder=FOLDER)
        gt = pm.ground_truth(scene, spp=SPP, kinds=["visibility"])
        for name, method, params in SETTINGS:
            result = renderer.render(scene, method, outputs=["visibility", "object_id"], **params)
            m = metrics.compare_images(result.visibility, gt, object_id=result.object_id)
            out[name][seed] = {"rmse": m["visibility_rmse_penumbra"], "stray": m["stray_fraction"], "penumbra_pixels": m["penumbra_pixels"]}
            IMAGES[(name, seed, size)] = (result.visibility, gt.visibility)
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    (ARTIFACTS / f"table_{size}.json").write_text(json.dumps(out, indent=1))
    return out


IMAGES: dict[tuple[str, int, int], tuple[np.ndarray, np.ndarray]] = {}


@pytest.fixture(scope="module")
def table() -> dict[str, dict[int, dict[str, float]]]:
    return measure(SEEDS, SIZE)


def fail_with_images(what: str, name: str, seeds: list[int], size: int = SIZE) -> None:
    folders = [leave_images(f"{name}-seed{seed}-{size}", *IMAGES[(name, seed, size)], ARTIFACTS) for seed in seeds if (name, seed, size) in IMAGES]
    pytest.fail(f"{what}; method, truth and difference images in {[str(f) for f in folders]}")


def test_the_generator_is_deterministic_and_draws_every_kind_of_scene() -> None:
    a, b = scenes.generate(7, width=16, folder=FOLDER), scenes.generate(7, width=16, folder=FOLDER)
    assert a.name == b.name
    for ma, mb in zip(a.meshes, b.meshes):
        np.testing.assert_array_equal(np.asarray(ma.vertices), np.asarray(mb.vertices))
    specs = [scenes.generated_spec(s) for s in SEEDS]
    assert len({s.mesh for s in specs}) >= 12, "most meshes of the pool drawn"
    assert sum(s.room for s in specs) >= 3 and sum(s.second_mesh is not None for s in specs) >= 6
    assert sum(s.tumbled for s in specs) >= 8 and sum(s.lift > 0 for s in specs) >= 8
    assert min(s.elevation for s in specs) < 30 and max(s.elevation for s in specs) > 80
    assert min(s.light_radius for s in specs) < 0.15 and max(s.light_radius for s in specs) > 0.8
    assert sum(s.floor_over_light_height > 4 for s in specs) >= 6
    assert min(s.scale for s in specs) < 0.2 and max(s.scale for s in specs) > 10


def test_the_generator_refuses_what_it_cannot_build(tmp_path: Path) -> None:
    with pytest.raises(penumbra.ParameterError, match="non-negative integer"):
        scenes.generate(-1, folder=FOLDER)
    with pytest.raises(penumbra.ParameterError, match="seed of digits"):
        scenes.get("generated:seven")
    with pytest.raises(penumbra.MeshError, match="cannot read"):
        scenes.generate(0, folder=tmp_path)


def test_every_generated_scene_shows_a_penumbra(table: dict[str, dict[int, dict[str, float]]]) -> None:
    # At least 1% of the image in penumbra: an RMSE over fewer pixels says little.
    few = {seed: row["penumbra_pixels"] for seed, row in table["hard"].items() if row["penumbra_pixels"] < 0.01 * SIZE * SIZE}
    assert not few, f"scenes with almost no penumbra in view: {few}"


def summary(rows: dict[int, dict[str, float]], hard: dict[int, dict[str, float]]) -> dict[str, float]:
    rmse = [r["rmse"] for r in rows.values()]
    over_hard = [rows[s]["rmse"] / hard[s]["rmse"] for s in rows]
    stray = [r["stray"] for r in rows.values()]
    return {
        "median": statistics.median(rmse), "worst": max(rmse),
        "worst_over_hard": max(over_hard), "median_stray": statistics.median(stray), "worst_stray": max(stray),
    }


# What each setting measured on seeds 0-39 at 96x96 (the table this test
# writes to test-artifacts/generated/table_96.json). The renders and the
# cached truth are deterministic; the slack (5% + 0.003 in RMSE, 0.2% of
# pixels in stray) leaves room for a truth rendered on another CPU.
MEASURED: dict[str, dict[str, float]] = {
    # Since issue 30 the light's frustum covers the casters and their
    # penumbrae, not the floor (light_frustum.rs): 38 of the 40 scenes take
    # one frustum where 36 took cube faces, its texels finer. Every median
    # fell (hard 0.291, pcss 0.0728, backprojection 0.0471, pvm 0.134, pvmf
    # 0.0701, wedges 0.117 before) but pvmf paper's (0.1585 -> 0.1651);
    # pvmf's worst rose 0.2033 -> 0.2094 (seed 1), pvmf area's worst stray
    # 0.0322 -> 0.0351 (seed 37).
    "hard": {"median": 0.2872, "worst": 0.3651, "median_stray": 0.0001, "worst_stray": 0.0019},
    # With its horizon repair (the default; 0.112 / 0.364 with the paper's
    # centre test), search taps spread by scale, blocker_test "behind" and
    # blocker_depth "cone_farthest" (the defaults, docs/methods/pcss.md;
    # with the mean blocker depth, "pcss mean", 0.0657 / 0.1953 / 0.0163:
    # the farthest in-cone blocker is better on 24 of the 40 scenes by more
    # than 0.003, worse on none).
    "pcss": {"median": 0.0640, "worst": 0.1686, "median_stray": 0.0001, "worst_stray": 0.0143},
    "pcss mean": {"median": 0.0657, "worst": 0.1953, "median_stray": 0.0002, "worst_stray": 0.0163},
    # The paper's blocker test. The floor slab and a room's walls are out of
    # the shadow map (casters.rs: they hide nothing), so it finds no
    # blockers in them. (0.0673 / 0.1952 / 0.0163 with the mean depth.)
    "pcss plane": {"median": 0.0649, "worst": 0.1685, "median_stray": 0.0001, "worst_stray": 0.0143},
    # The paper's search: uniform taps, the plane test and the mean depth
    # (0.082 / 0.336 before issue 30's fit: over the casters alone its
    # search disk holds fewer empty texels).
    "pcss paper search": {"median": 0.0651, "worst": 0.1952, "median_stray": 0.0002, "worst_stray": 0.0149},
    # Fernando 2005 as written (penumbra.comparison.PAPER["pcss"]): the
    # paper's search without the horizon repair.
    "pcss paper": {"median": 0.0892, "worst": 0.2007, "median_stray": 0.0002, "worst_stray": 0.0149},
    # The option: its median above the default's (0.0793 / 0.1965 / 0.0265
    # with the mean depth).
    "pcss cone": {"median": 0.0739, "worst": 0.1691, "median_stray": 0.0001, "worst_stray": 0.0143},
    # The option estimate="area" (the filter's failing taps weighted by the
    # light their occluders hide, in their own cones), with the behind test
    # (0.0749 / 0.1843 / 0.0241 with the mean depth).
    "pcss area": {"median": 0.0687, "worst": 0.1652, "median_stray": 0.0002, "worst_stray": 0.0223},
    # Kernels crossing a cube face go down at most 2 kernel caps (issue 30).
    "backprojection": {"median": 0.0433, "worst": 0.1466, "median_stray": 0.0001, "worst_stray": 0.0109},
    # The defaults since issue 28 (docs/methods/pvm.md): edges="chain" (the
    # nearest edge's silhouette loop walked where the map sees the light's
    # centre; "pvm two", the default before, 0.1221 / 0.1899: lower on 18
    # scenes, higher on 2), volume_map_size="auto", lookup="3x3", umbra_test="rim" and Eq. 4.1's disk fraction; the
    # paper's 4.1.3 and 4.2 (penumbra.comparison.PAPER["pvm"]: one edge per
    # texel of a map-sized volume map, read at the pixel's texel, and 4.2's
    # 3k^2 - 2k^3); and the same with Eq. 4.1's k, the default before the
    # 3x3 lookup (lower on 34 of the 40 scenes with it; its worst stray share
    # rose 1.42% -> 1.60%, seed 37). With umbra_test="rim" (the default) the
    # median stray share fell 0.0014 -> 0.0009, the errors the same. The map
    # bound (map_samples=16, the default since; "pvm no map bound" is the
    # default before it) lowered the median 0.1192 -> 0.0960, lower on 35
    # scenes and higher on none (docs/methods/pvm.md). Its margin then was
    # 1/16, under the spiral's own error beneath a straight edge (0.143 at
    # 16 points: tests/test_map_rays.py), and it streaked straight edges;
    # with map_margin (0.17 at 16), map_march=8 and the bound from both
    # sides where the map sees the light's centre (map_bound="both"; "pvm
    # upper bound" from above only) the median was 0.0979. With the texel
    # band in the margin, k taken past the band to the rays' fraction
    # (`toward`), cube maps' light points at their depth along the
    # receiver's face (goal_depth) and map_control the default (the rays
    # compared with the edge's half-plane at the same points; "pvm no
    # control" without it): 0.0802, lower on 39 scenes than without the
    # control, higher on none (docs/methods/pvm.md). "pvm two" has the bound
    # too (0.1221 without it). Since issue 28's stop 64 the bound also raises
    # k where the map hides the centre behind a solid caster's front
    # (map_bound="solid") with 32 rays: "pvm before solid" is the default
    # before (16 rays, "both"), "pvm 16 rays" the new rule alone (lower on
    # 24 scenes, higher on none); every pvm row with the bound moved with
    # it. Before: "pvm two" 0.0807 / 0.1359, "pvm upper bound" 0.0895 /
    # 0.1751, "pvm no control" 0.0871 / 0.1528, "pvm no solids" 0.0802 /
    # 0.1543 / 0.0113.
    "pvm": {"median": 0.0584, "worst": 0.1216, "median_stray": 0.0001, "worst_stray": 0.0080},
    "pvm before solid": {"median": 0.0790, "worst": 0.1359, "median_stray": 0.0001, "worst_stray": 0.0085},
    "pvm 16 rays": {"median": 0.0670, "worst": 0.1298, "median_stray": 0.0001, "worst_stray": 0.0085},
    "pvm no solids": {"median": 0.0728, "worst": 0.1447, "median_stray": 0.0001, "worst_stray": 0.0106},
    "pvm two": {"median": 0.0581, "worst": 0.1216, "median_stray": 0.0001, "worst_stray": 0.0080},
    "pvm upper bound": {"median": 0.0865, "worst": 0.1706, "median_stray": 0.0001, "worst_stray": 0.0080},
    "pvm no control": {"median": 0.0631, "worst": 0.1256, "median_stray": 0.0001, "worst_stray": 0.0080},
    "pvm no map bound": {"median": 0.1192, "worst": 0.1899, "median_stray": 0.0009, "worst_stray": 0.0160},
    "pvm paper": {"median": 0.1325, "worst": 0.1883, "median_stray": 0.0013, "worst_stray": 0.0142},
    "pvm one edge": {"median": 0.1254, "worst": 0.1966, "median_stray": 0.0013, "worst_stray": 0.0142},
    # The defaults since issue 31 (the disk kernel, no blur, radius offsets,
    # the umbra skipped, s_e 0.02: "pvmf recommended" before), the same with
    # the option blocker_test="behind", and the paper's settings (the
    # defaults before issue 31, penumbra.comparison.PAPER["pvmf"]).
    # Since occluder_distance="darker" became the default (docs/methods/pvmf.md):
    # 0.0615 / 0.2094 / 0.0003 / 0.0604 before, with 5.2's d_o ("pvmf nearest
    # volume no map bound"); better by more than 0.003 on 26 scenes and
    # worse on none. Since the map bound became the default (map_samples=16,
    # with map_solids, on the filtered pixels; docs/methods/pvmf.md; "pvmf no
    # map bound" is the default before it, "pvmf no solids" the bound
    # without the solid layers, "pvmf 32 rays" twice the rays): 0.0553 /
    # 0.1960 / 0.0001 / 0.0268 before; every option below has the bound too
    # (before it: behind 0.0503 / 0.1960, area 0.0596 / 0.1771, farthest
    # edge 0.0786 / 0.2374, nearest volume 0.0615 / 0.2094). With
    # map_bound="solid" (the default since stop 64) pvmf moved by under
    # 0.0015 but for "farthest edge" (worst 0.2311 -> 0.1796).
    "pvmf": {"median": 0.0489, "worst": 0.1378, "median_stray": 0.0001, "worst_stray": 0.0128},
    "pvmf no map bound": {"median": 0.0553, "worst": 0.1960, "median_stray": 0.0001, "worst_stray": 0.0268},
    "pvmf 32 rays": {"median": 0.0443, "worst": 0.1161, "median_stray": 0.0001, "worst_stray": 0.0117},
    "pvmf no solids": {"median": 0.0489, "worst": 0.1731, "median_stray": 0.0001, "worst_stray": 0.0258},
    "pvmf behind": {"median": 0.0477, "worst": 0.1220, "median_stray": 0.0001, "worst_stray": 0.0131},
    "pvmf paper": {"median": 0.1651, "worst": 0.2806, "median_stray": 0.0046, "worst_stray": 0.0589},
    # The option estimate="area" (each failing tap weighted by the light its
    # occluder hides, in its own cone).
    "pvmf area": {"median": 0.0521, "worst": 0.1146, "median_stray": 0.0001, "worst_stray": 0.0154},
    # The other choices of occluder_distance (docs/methods/pvmf.md): d_o from
    # the farthest enclosing edges (every scene's stray pixels under 0.5%, at
    # a higher median), and 5.2's, the mask's (the default before "darker"),
    # with the bound and without it.
    "pvmf farthest edge": {"median": 0.0715, "worst": 0.1796, "median_stray": 0.0001, "worst_stray": 0.0018},
    "pvmf nearest volume": {"median": 0.0527, "worst": 0.1351, "median_stray": 0.0001, "worst_stray": 0.0138},
    "pvmf nearest volume no map bound": {"median": 0.0615, "worst": 0.2094, "median_stray": 0.0003, "worst_stray": 0.0604},
    # With the map bound (map_samples=32 since this stop, 16 before; map_march=8, map_bound="both": the default since,
    # docs/methods/wedges.md); "wedges no map bound" is the default before,
    # "wedges upper bound" the bound from above only.
    # With the bound's texel band, `toward` and goal_depth (as pvm's): 0.0753
    # / 0.2262 before them, 0.0732 / 0.1718 after them at 16 rays (lower on
    # 35 scenes, higher on 1: seed 9, 0.0734 -> 0.0783); with 32 rays, the
    # default since, 0.0625 / 0.1470. "wedges upper bound" from above only.
    # With map_bound="solid" (the default since stop 64; "wedges before
    # solid" the default before): lower on 21 scenes, higher on none.
    "wedges": {"median": 0.0596, "worst": 0.1086, "median_stray": 0.0001, "worst_stray": 0.0019},
    "wedges before solid": {"median": 0.0606, "worst": 0.1086, "median_stray": 0.0001, "worst_stray": 0.0019},
    "wedges no solids": {"median": 0.0625, "worst": 0.1464, "median_stray": 0.0001, "worst_stray": 0.0134},
    "wedges no map bound": {"median": 0.1019, "worst": 0.3128, "median_stray": 0.0001, "worst_stray": 0.0136},
    "wedges upper bound": {"median": 0.0736, "worst": 0.1487, "median_stray": 0.0001, "worst_stray": 0.0019},
    # Since map_solids (the default; passes/solid_layers.rs), every setting
    # with the map bound: "wedges no solids" and "pvm no solids" are the
    # defaults before it. Before it, "wedges upper bound" was 0.0790 /
    # 0.1861 / 0.0134, "wedges independent" 0.0668 / 0.1693 / 0.0132, "pvm
    # two" 0.0834 / 0.1543 / 0.0113, "pvm upper bound" 0.0906 / 0.1899,
    # "pvm no control" 0.0890 / 0.1692.
    # The option, not the default: separate objects multiplied
    # (docs/methods/wedges.md; 0.1098 / 0.2642 without the map bound).
    "wedges independent": {"median": 0.0606, "worst": 0.1603, "median_stray": 0.0001, "worst_stray": 0.0019},
}


@pytest.mark.parametrize("name", [n for n, _, _ in SETTINGS])
def test_each_method_holds_its_measured_accuracy_over_the_suite(name: str, table: dict[str, dict[int, dict[str, float]]]) -> None:
    got = summary(table[name], table["hard"])
    if name not in MEASURED:
        pytest.skip(f"not measured yet: {got}")
    want = MEASURED[name]
    failed = {}
    for key in ("median", "worst"):
        if got[key] > want[key] * 1.05 + 0.003:
            failed[key] = (round(got[key], 4), want[key])
    for key in ("median_stray", "worst_stray"):
        if got[key] > want[key] + 0.002:
            failed[key] = (round(got[key], 4), want[key])
    if failed:
        worst = sorted(table[name], key=lambda s: -table[name][s]["rmse"])[:3]
        fail_with_images(f"{name}: {failed} (measured, bound)", name, worst)


def test_a_caster_near_the_light_does_not_light_a_farther_casters_umbra(table: dict[str, dict[int, dict[str, float]]]) -> None:
    # Seed 37: a boot 0.3 under a light of radius 0.32 above a koala. The
    # boot's volumes, nearest the light, cover the koala's shadow, so the
    # mask's d_e (5.2's d_o) is the boot's and the filter, sized for the
    # boot's penumbra, lights the koala's umbra: 6.04% stray pixels with
    # 5.2's d_o, 2.68% with occluder_distance="darker" (the default: a
    # second filter for the koala's own distance where a shadowed receiver's
    # occluder lies beyond the boot's edges), 0.49% with d_o from the
    # farthest enclosing edges, each the filter alone (map_samples=0); with
    # the map bound (the default since issue 28) "darker" 0.37%, 5.2's d_o
    # 0.34%: the rays find the koala whichever d_o sizes the filter.
    paper = table["pvmf nearest volume no map bound"][37]["stray"]
    for name, share in (("pvmf no map bound", 0.6), ("pvmf", 0.1), ("pvmf farthest edge", 0.25)):
        got = table[name][37]["stray"]
        if got > share * paper:
            fail_with_images(f"{name}: {got:.4f} stray pixels on seed 37 against 5.2's d_o's {paper:.4f}", name, [37])


@pytest.mark.parametrize("method", ["pvm", "wedges"])
def test_the_map_bound_lowers_the_error_on_most_scenes(method: str, table: dict[str, dict[int, dict[str, float]]]) -> None:
    """The map bound (map_samples=16, map_march=8, map_bound="both":
    passes/map_rays.wgsl) against the same method without it and with the
    bound from above only. Measured on seeds 0-39 (changes over 0.001):
    with the bound from above against none, pvm lower on 35 scenes and
    wedges on 38, higher on none; from both sides against from above, pvm
    lower on 27, wedges on 37, higher on none (with the texel band,
    `toward` and, for pvm, map_control). Held with room: each step lower on at least 15
    scenes and on three times as many as it raises, and higher by more
    than 0.005 on at most 2."""
    steps = [(f"{method} no map bound", f"{method} upper bound"), (f"{method} upper bound", method)]
    for before, after in steps:
        lower = [s for s in SEEDS if table[after][s]["rmse"] < table[before][s]["rmse"] - 0.001]
        higher = [s for s in SEEDS if table[after][s]["rmse"] > table[before][s]["rmse"] + 0.001]
        worse = [s for s in higher if table[after][s]["rmse"] > table[before][s]["rmse"] + 0.005]
        if len(lower) < 3 * len(higher) or len(lower) < 15 or len(worse) > 2:
            fail_with_images(f"{before} -> {after}: lower on {lower}, higher on {higher}", after, higher[:3])


@pytest.mark.parametrize("method", ["pvm", "wedges"])
def test_the_solid_layers_lower_the_error_and_raise_it_nowhere(method: str, table: dict[str, dict[int, dict[str, float]]]) -> None:
    """map_solids (passes/solid_layers.rs) against the same method without
    it. Measured on seeds 0-39 (changes over 0.001): wedges lower on 11
    scenes (1, 3, 8, 14, 22, 23, 27, 29, 35, 37, 38), pvm on 19, higher on
    none; wedges' stray pixels on seeds 1, 37 and 38 from 1.12%, 0.66%,
    1.34% to 0.02%, 0.12%, 0.00% (the umbra at a resting mesh's contact,
    under a second caster), its RMSE there 0.146, 0.091, 0.117 -> 0.087,
    0.069, 0.060. Held: lower on at least 8, higher on none, and no
    scene's stray share up by more than 0.1%."""
    on, off = table[method], table[f"{method} no solids"]
    lower = [s for s in SEEDS if on[s]["rmse"] < off[s]["rmse"] - 0.001]
    higher = [s for s in SEEDS if on[s]["rmse"] > off[s]["rmse"] + 0.001]
    more_stray = [s for s in SEEDS if on[s]["stray"] > off[s]["stray"] + 0.001]
    if len(lower) < 8 or higher or more_stray:
        fail_with_images(f"{method}: map_solids lower on {lower}, higher on {higher}, more stray pixels on {more_stray}", method, (higher + more_stray)[:3])


def test_pvmf_map_bound_lowers_the_error_and_meets_more_of_the_bar(table: dict[str, dict[int, dict[str, float]]]) -> None:
    """pvmf's option map_samples (16 rays; docs/methods/pvmf.md) against
    its default (5.2's filter alone): measured lower on 31 scenes by more
    than 0.001, higher on none, no stray share up; issue 28's bar missed on
    2 scenes (2, 34) against 5 (1, 2, 34, 37, 38), and on 1 (2) with 32
    rays; without the solid layers the bound still misses all 5. Held: lower
    on at least 25, higher by more than 0.005 on none, the misses as measured
    or fewer."""
    on, off = table["pvmf"], table["pvmf no map bound"]
    lower = [s for s in SEEDS if on[s]["rmse"] < off[s]["rmse"] - 0.001]
    worse = [s for s in SEEDS if on[s]["rmse"] > off[s]["rmse"] + 0.005]
    more_stray = [s for s in SEEDS if on[s]["stray"] > off[s]["stray"] + 0.001]
    if len(lower) < 25 or worse or more_stray:
        fail_with_images(f"pvmf: the map bound lower on {lower}, worse on {worse}, more stray pixels on {more_stray}", "pvmf", (worse + more_stray)[:3])
    missed = {name: within_half_of_hard(table, name) for name in ("pvmf", "pvmf 32 rays")}
    assert set(missed["pvmf"]) <= {2, 34} and set(missed["pvmf 32 rays"]) <= {2}, missed


@pytest.mark.parametrize("method", ["pvm", "wedges"])
def test_the_solid_bound_lowers_the_error_and_raises_it_nowhere(method: str, table: dict[str, dict[int, dict[str, float]]]) -> None:
    """map_bound="solid" (the bound also raises k where the map hides the
    light's centre behind a solid caster's front whose layers hold every
    surface behind it: passes/map_rays.wgsl's `solid_in_front`) against
    "both" (raised only where the map sees the centre), pvm at 16 rays
    both ("pvm 16 rays" against "pvm before solid"). Measured on seeds
    0-39 (changes over 0.001): pvm lower on 24, wedges on 21, higher on
    none, no stray share up by 0.05%. Raised behind any surface (a build
    not kept) it lit more of seed 2's umbra (pvm 0.85% -> 1.61% stray:
    hollow teapots, more surfaces than the layers hold) and raised seed 28
    (an open aeroplane, 0.112 -> 0.127). Held: lower on at least 15,
    higher on none, no stray share up by more than 0.1%."""
    before, after = (("pvm before solid", "pvm 16 rays"), ("wedges before solid", "wedges"))[method == "wedges"]
    a, b = table[before], table[after]
    lower = [s for s in SEEDS if b[s]["rmse"] < a[s]["rmse"] - 0.001]
    higher = [s for s in SEEDS if b[s]["rmse"] > a[s]["rmse"] + 0.001]
    more_stray = [s for s in SEEDS if b[s]["stray"] > a[s]["stray"] + 0.001]
    if len(lower) < 15 or higher or more_stray:
        fail_with_images(f"{before} -> {after}: lower on {lower}, higher on {higher}, more stray pixels on {more_stray}", after, (higher + more_stray)[:3])


def within_half_of_hard(table: dict[str, dict[int, dict[str, float]]], name: str) -> list[int]:
    """The seeds on which `name` misses issue 28's bar: a penumbra RMSE above
    0.5x hard's, or more than 0.5% stray pixels."""
    return [s for s, row in table[name].items() if row["rmse"] > 0.5 * table["hard"][s]["rmse"] or row["stray"] > 0.005]


# Issue 28's targets. Missed today (the counts of scenes missed, seeds 0-39):
# wedges none since map_solids (3 without it: 1, 37, 38, on stray pixels alone; 8 without the map bound, 12
# before issue 30's caster-fitted frustum, 38 before its coverage term and
# overlap gate), pvm 2 (2, 37; 5 without map_control or with the bound from
# above only, 8 without the bound, 13 without its rim test too, 15 with one edge
# per texel of a map-sized volume map read at the pixel's texel, 16 with
# the paper's falloff too), pvmf 2 (seeds 2, 34: 1.28% stray pixels, and
# 0.138 against 0.135; 5 without the map bound, its default before issue
# 28's stop 63: 1, 2, 34, 37, 38; 7 with 5.2's
# d_o, its default before occluder_distance="darker"; 27 with the paper's
# settings, its defaults until issue 31; pcss misses 4: 1, 2, 37, 38, and
# 28 too with the mean blocker depth). Met: pvm's median 0.0584 since
# map_bound="solid" and 32 rays, its defaults since stop 64 (0.0670 with
# 16 rays, 0.0790 before both, 0.0802 before map_solids too, 0.1192 without
# the map bound, 0.1325 as the paper builds it) against pcss's 0.0640
# (0.0657 with the mean blocker depth); pvmf's
# 0.0489 (0.0553 without the map bound), and wedges' 0.0596 (0.0625 with 32 rays, its default since stop 59
# (0.0732 with 16, 0.1019 without the map bound; on the slow suite, which
# nothing was chosen on, 0.0591 against pcss's 0.0607). Strict: each
# starts failing when the method meets it.
@pytest.mark.parametrize("name", ["wedges"] + [pytest.param(n, marks=pytest.mark.xfail(strict=True, reason="issue 28: not met yet")) for n in ("pvm", "pvmf")])
def test_issue_28_every_scene_within_half_of_hard_and_few_stray_pixels(name: str, table: dict[str, dict[int, dict[str, float]]]) -> None:
    missed = within_half_of_hard(table, name)
    if missed:
        fail_with_images(f"{name} misses 0.5x hard's penumbra RMSE or 0.5% stray pixels on {len(missed)} scenes: seeds {missed}", name, missed[:3])


@pytest.mark.parametrize("name", ["pvm", "wedges", "pvmf"])
def test_issue_28_median_at_most_pcss(name: str, table: dict[str, dict[int, dict[str, float]]]) -> None:
    median = statistics.median(r["rmse"] for r in table[name].values())
    pcss = statistics.median(r["rmse"] for r in table["pcss"].values())
    assert median <= pcss, f"{name}'s median penumbra RMSE {median:.4f} above pcss's {pcss:.4f}"


@pytest.mark.slow
def test_the_slow_suite_at_160_pixels() -> None:
    """60 more scenes at 160x160: every setting's median and worst printed
    and written to test-artifacts/generated/table_160.json, held to the
    faithful bars of the default suite's medians (with the same slack)."""
    table = measure(SLOW_SEEDS, SLOW_SIZE)
    failed = {}
    for name, _, _ in SETTINGS:
        got = summary(table[name], table["hard"])
        print(name, {k: round(v, 4) for k, v in got.items()})
        if got["median"] > MEASURED[name]["median"] * 1.25 + 0.01:
            failed[name] = (round(got["median"], 4), MEASURED[name]["median"])
    assert not failed, f"medians on the slow suite well above the default suite's: {failed}"

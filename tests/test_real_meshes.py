"""Real meshes from ../shared/meshes with every method (issue 8), and the
volume methods held to their measured accuracy on them against Mitsuba
ground truth (issue 15; docs/real_meshes.md has the tables these bounds come
from, `penumbra bench --config benchmarks/real_meshes.toml` writes them).

Skipped when the meshes are absent (they are never copied into the
repository); the accuracy tests also need Mitsuba. Ground truth is cached
like `penumbra compare`'s (`$PENUMBRA_CACHE_DIR`, default ~/.cache/penumbra):
the first run renders it, about 25 s. Sponza (66k triangles) and the full
bunny are `slow` in the render-or-refuse table."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import penumbra
from penumbra import metrics
from penumbra.comparison import PAPER
from stress_scenes import FAST, MESHES, METHODS, VOLUME_METHODS, check_images

# mesh file -> (the error the volume methods give with open_edges="error", or None; slow)
# The reasons come from ../shared/meshes/SOURCES.md's topology table.
NOT_MANIFOLD = (penumbra.MeshError, ["not a 2-manifold", "open_edges='silhouette'"])
NOT_CLOSED = (penumbra.MeshError, ["not closed", "boundary edges", "open_edges='silhouette'"])
EXPECTED: dict[str, tuple[tuple[type[Exception], list[str]] | None, bool]] = {
    "cube.obj": (None, False),
    "spot.obj": (None, False),
    "teapot-mcguire-closed.obj": (None, False),
    # Open (5 holes in the bottom), edge-manifold.
    "bun_zipper.ply": (NOT_CLOSED, True),
    # 70 non-manifold edges, 40 duplicate faces, holes.
    "bun_zipper_res4.ply": (NOT_MANIFOLD, False),
    # Open boxes with a duplicated side face each: one face once welded
    # (issue 27), which leaves the boxes' 16 open edges.
    "CornellBox-Original.obj": (NOT_CLOSED, False),
    # 481 non-manifold edges, 4712 boundary edges.
    "sponza.obj": (NOT_MANIFOLD, True),
}


def cases() -> list:
    out = []
    for name, (_, slow) in EXPECTED.items():
        for method in METHODS:
            marks = [pytest.mark.slow] if slow else []
            out.append(pytest.param(name, method, marks=marks, id=f"{name}-{method}"))
    return out


@pytest.fixture(scope="module")
def loaded() -> dict[str, penumbra.Scene]:
    if not MESHES.is_dir():
        pytest.skip(f"the shared meshes are not at {MESHES.resolve()}")
    return {}


def scene_of(loaded: dict[str, penumbra.Scene], name: str) -> penumbra.Scene:
    if name not in loaded:
        loaded[name] = penumbra.scenes.from_mesh(str(MESHES / name), width=48, height=48)
    return loaded[name]


@pytest.mark.parametrize("name, method", cases())
def test_real_mesh_renders_and_strict_topology_names_the_reason(renderer: penumbra.Renderer, loaded: dict[str, penumbra.Scene], name: str, method: str) -> None:
    """Every mesh renders with every method's defaults (the volume methods
    take edges that are not two-sided as silhouette edges where all their
    faces lie on one side); with open_edges="error" the volume methods refuse
    open and non-manifold meshes, naming the mesh and what to do."""
    scene = scene_of(loaded, name)
    result = renderer.render(scene, method, **FAST[method])
    check_images(result, f"{name}/{method}")
    assert (result.object_id == 1).any(), "the mesh is in view"
    error = EXPECTED[name][0]
    if method in VOLUME_METHODS:
        if error is None:
            check_images(renderer.render(scene, method, open_edges="error", **FAST[method]))
            return
        with pytest.raises(error[0]) as info:
            renderer.render(scene, method, open_edges="error", **FAST[method])
        message = str(info.value)
        assert f"'{name}'" in message, f"the message names the mesh: {message}"
        for word in error[1]:
            assert word in message, f"{word!r} not in {message!r}"


def test_cornell_box_relative_indices_are_resolved(loaded: dict[str, penumbra.Scene]) -> None:
    """trimesh 5.2 misreads the Cornell box's relative (negative) face
    indices (SOURCES.md); from_mesh reads such OBJ files itself. The file's
    box spans 2.02 x 1.99 x 2.03 (SOURCES.md's bounding box); from_mesh scales
    its largest extent to 2.5. (trimesh's reading spans 1.15 in x.)"""
    mesh = scene_of(loaded, "CornellBox-Original.obj").meshes[1]
    extents = mesh.vertices.max(axis=0) - mesh.vertices.min(axis=0)
    assert len(mesh.faces) == 36
    np.testing.assert_allclose(extents, 2.5 * np.array([2.02, 1.99, 2.03]) / 2.03, atol=0.01)


# ---------------------------------------------------------------------------
# Accuracy against Mitsuba ground truth (issue 15)

SIZE = 160
GT_SPP = 1024
ARTIFACTS = Path(__file__).resolve().parents[1] / "test-artifacts" / "real_meshes"
CONFIGS: dict[str, tuple[str, dict[str, Any]]] = {
    "pvm": ("pvm", {}),  # its defaults since issue 28 (docs/methods/pvm.md)
    "pvm-paper": ("pvm", PAPER["pvm"]),  # 4.1.3 and 4.2 as the paper builds them
    # The paper's but Eq. 4.1's k: the default before edges="two" (now "chain"), volume_map_size="auto", lookup="3x3".
    "pvm-one-edge": ("pvm", {"edges": "one", "volume_map_size": "map", "lookup": "texel", "umbra_test": "none", "map_samples": 0}),
    "pvmf": ("pvmf", {}),  # its defaults, the settings docs/real_meshes.md once recommended over the paper's
}

# Penumbra visibility RMSE measured by benchmarks/real_meshes.toml (160 x 160,
# ground truth at 1024 samples, whose own noise is 0.002-0.003 here) per
# scene and configuration; each test allows it 15% and 0.005 more. pvmf's
# since occluder_distance="darker" became its default (issue 28; the
# benchmark's row "occluder_distance=nearest_volume" has the values before);
# pvm's since the map bound (map_samples=16, map_march=8, map_bound="both",
# with its texel band and map_control=True since this stop) joined
# edges="chain", volume_map_size="auto" and lookup="3x3" in its defaults
# (issue 28; the row
# "edges=one lookup=texel map_samples=0 ..." is pvm-one-edge, the row
# "falloff=True edges=one ..." pvm-paper). Rerun after map_solids (pvm's
# default: 0.0735 -> 0.0731 on spot close r=0.8, 0.0636 -> 0.0616 on the
# teapot close r=0.8, 0.0627 -> 0.0622 on spot's wide floor, the rest
# within 0.0002) and pvmf's map bound (its default since issue 28's stop
# 63; the row "map_samples=0" has the values before: lower on 11 of the 15
# scenes, by up to 0.0064 on the teapot's wide floor, higher on none).
# Rerun after map_bound="solid" and 32 rays became pvm's defaults (issue
# 28's stop 64; the row "map_bound=both map_samples=16" has the values
# before: spot close r=0.8 0.0731 -> 0.0617, the teapot's wide floor 0.0638
# -> 0.0573, lower on 9 of the 15 scenes, higher on the Cornell box at
# r=0.3, 0.0107 -> 0.0126).
MEASURED: dict[str, dict[str, float]] = {
    "cube.obj close r=0.3": {"pvm": 0.0062, "pvm-paper": 0.0425, "pvm-one-edge": 0.0154, "pvmf": 0.0165},
    "cube.obj close r=0.8": {"pvm": 0.0421, "pvm-paper": 0.0681, "pvm-one-edge": 0.0523, "pvmf": 0.0426},
    "cube.obj wide_floor r=0.3": {"pvm": 0.0151, "pvm-paper": 0.0781, "pvm-one-edge": 0.0381, "pvmf": 0.0406},
    "spot.obj close r=0.3": {"pvm": 0.0386, "pvm-paper": 0.0962, "pvm-one-edge": 0.0713, "pvmf": 0.0396},
    "spot.obj close r=0.8": {"pvm": 0.0617, "pvm-paper": 0.1118, "pvm-one-edge": 0.0964, "pvmf": 0.0449},
    "spot.obj wide_floor r=0.3": {"pvm": 0.0513, "pvm-paper": 0.1019, "pvm-one-edge": 0.0875, "pvmf": 0.0457},
    "teapot-mcguire-closed.obj close r=0.3": {"pvm": 0.0167, "pvm-paper": 0.0655, "pvm-one-edge": 0.0243, "pvmf": 0.0279},
    "teapot-mcguire-closed.obj close r=0.8": {"pvm": 0.0525, "pvm-paper": 0.1054, "pvm-one-edge": 0.0860, "pvmf": 0.0477},
    "teapot-mcguire-closed.obj wide_floor r=0.3": {"pvm": 0.0573, "pvm-paper": 0.1031, "pvm-one-edge": 0.0782, "pvmf": 0.0300},
}
# Issue 15's targets, which every scene meets (the benchmark's targets table):
# penumbra RMSE at most half of hard's; stray pixels under 0.5%; pvmf's
# masked pixels at most 3x the true penumbra's (measured at most 2.2x) and
# pvm's in-volume pixels at most 1.5x (measured at most 1.3x); pvmf (its
# defaults) within 1.2x of pcss's error (measured at most 0.6x).
RATIO_TO_HARD = 0.5
STRAY_PERCENT = 0.5
VOLUME_RATIO = {"pvm": 1.5, "pvmf": 3.0}
RATIO_TO_PCSS = 1.2


def suite() -> dict[str, penumbra.Scene]:
    if not MESHES.is_dir():
        return {}
    return penumbra.scenes.real_mesh_suite(str(MESHES), width=SIZE, height=SIZE)


SUITE = suite()


@pytest.fixture(scope="module")
def truth() -> dict[str, np.ndarray]:
    """Ground-truth visibility per suite scene, rendered (or read from the cache) on first use."""
    if not MESHES.is_dir():
        pytest.skip(f"the shared meshes are not at {MESHES.resolve()}")
    pytest.importorskip("mitsuba", reason="Mitsuba 3 is not installed")
    return {}


def truth_of(truth: dict[str, np.ndarray], name: str, scene: penumbra.Scene) -> np.ndarray:
    if name not in truth:
        from penumbra import mitsuba as pm

        truth[name] = pm.ground_truth(scene, spp=GT_SPP, kinds=("visibility",)).visibility
    return truth[name]


def difference_image(visibility: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """RGB: red where the method is brighter than the truth, blue where darker, grey where equal."""
    d = np.asarray(visibility, dtype=np.float32) - np.asarray(gt, dtype=np.float32)
    out = np.full((*d.shape, 3), 0.2, dtype=np.float32)
    out[..., 0] += np.clip(d, 0, 1) * 0.8
    out[..., 2] += np.clip(-d, 0, 1) * 0.8
    return out


def leave_images(test_id: str, visibility: np.ndarray, gt: np.ndarray, artifacts: Path = ARTIFACTS) -> Path:
    """Writes the method's visibility, the truth and their difference as PNGs
    under test-artifacts/real_meshes/<test_id>/; returns the folder."""
    folder = artifacts / re.sub(r"[^A-Za-z0-9_.=-]+", "_", test_id)
    folder.mkdir(parents=True, exist_ok=True)
    penumbra.write_image(folder / "method.png", visibility)
    penumbra.write_image(folder / "truth.png", gt)
    penumbra.write_image(folder / "difference.png", difference_image(visibility, gt))
    return folder


def check_against_truth(test_id: str, result: penumbra.RenderResult, gt: np.ndarray, bounds: dict[str, float], artifacts: Path = ARTIFACTS) -> dict[str, float]:
    """Measures the render against the truth and checks every bound given
    (`rmse`, `stray_percent`, `volume_ratio`); when one fails, leaves the
    method, truth and difference images behind and names them."""
    region = metrics.penumbra_region(gt)
    stray, out_of = metrics.stray_pixels(result.visibility, gt, result.object_id >= 0)
    in_volume = result.stats.get("pixels_in_volume", result.stats.get("masked_pixels"))
    measured = {
        "rmse": metrics.rmse(result.visibility, gt, region),
        "stray_percent": 100.0 * stray / max(out_of, 1),
        "volume_ratio": float(in_volume) / max(int(region.sum()), 1) if in_volume is not None else 0.0,
    }
    failed = {k: (measured[k], bound) for k, bound in bounds.items() if not measured[k] <= bound}
    if failed:
        folder = leave_images(test_id, result.visibility, gt, artifacts)
        pytest.fail(f"{test_id}: {failed} (measured, bound); method, truth and difference images in {folder}")
    return measured


@pytest.fixture(scope="module")
def baselines() -> dict[tuple[str, str], float]:
    """Penumbra RMSE of `hard` and `pcss` per suite scene, computed on first use."""
    return {}


def baseline(renderer: penumbra.Renderer, truth: dict[str, np.ndarray], baselines: dict[tuple[str, str], float], name: str, method: str) -> float:
    if (name, method) not in baselines:
        gt = truth_of(truth, name, SUITE[name])
        result = renderer.render(SUITE[name], method)
        baselines[(name, method)] = metrics.rmse(result.visibility, gt, metrics.penumbra_region(gt))
    return baselines[(name, method)]


@pytest.mark.parametrize("config", list(CONFIGS))
@pytest.mark.parametrize("name", list(SUITE) or ["(meshes absent)"])
def test_volume_methods_hold_their_measured_accuracy_on_real_meshes(
    renderer: penumbra.Renderer, truth: dict[str, np.ndarray], baselines: dict[tuple[str, str], float], name: str, config: str
) -> None:
    method, params = CONFIGS[config]
    scene = SUITE[name]
    gt = truth_of(truth, name, scene)
    hard = baseline(renderer, truth, baselines, name, "hard")
    bounds = {
        "rmse": RATIO_TO_HARD * hard,
        "stray_percent": STRAY_PERCENT,
        "volume_ratio": VOLUME_RATIO[method],
    }
    bounds["rmse"] = min(bounds["rmse"], 1.15 * MEASURED[name][config] + 0.005)
    if method == "pvmf":
        bounds["rmse"] = min(bounds["rmse"], RATIO_TO_PCSS * baseline(renderer, truth, baselines, name, "pcss"))
    check_against_truth(f"{name} {config}", renderer.render(scene, method, **params), gt, bounds)


def test_a_failed_bound_leaves_the_images_behind(renderer: penumbra.Renderer, truth: dict[str, np.ndarray], tmp_path: Path) -> None:
    """The check above on a render that must fail it (`hard`, held to pvm's
    bound): it fails, and the three images are there to look at (here in a
    temporary folder; the real tests leave them under test-artifacts/)."""
    name = "spot.obj close r=0.3"
    gt = truth_of(truth, name, SUITE[name])
    test_id = "deliberate failure hard"
    with pytest.raises(pytest.fail.Exception, match="images in"):
        check_against_truth(test_id, renderer.render(SUITE[name], "hard"), gt, {"rmse": 0.1}, tmp_path)
    folder = tmp_path / "deliberate_failure_hard"
    for image in ("method.png", "truth.png", "difference.png"):
        assert (folder / image).stat().st_size > 0, image


# The open and non-manifold meshes, seen close at the suite's two radii:
# penumbra RMSE measured by benchmarks/real_meshes.toml (pvm with its
# defaults since issue 28: 0.0814, 0.0982, 0.0693, 0.0890, 0.0264, 0.0653
# with one edge per texel of a map-sized volume map read at the pixel's
# texel; pvmf with its defaults), each allowed 15% and 0.005
# more, and the same targets as the closed meshes.
OPEN_MEASURED: dict[tuple[str, float], dict[str, float]] = {
    ("bun_zipper.ply", 0.3): {"pvm": 0.0699, "pvmf": 0.0656},
    ("bun_zipper.ply", 0.8): {"pvm": 0.0739, "pvmf": 0.0576},
    ("bun_zipper_res4.ply", 0.3): {"pvm": 0.0520, "pvmf": 0.0525},
    ("bun_zipper_res4.ply", 0.8): {"pvm": 0.0603, "pvmf": 0.0434},
    ("CornellBox-Original.obj", 0.3): {"pvm": 0.0107, "pvmf": 0.0363},
    ("CornellBox-Original.obj", 0.8): {"pvm": 0.0547, "pvmf": 0.0636},
}


@pytest.mark.parametrize("config", ["pvm", "pvmf"])
@pytest.mark.parametrize("mesh, radius", list(OPEN_MEASURED))
def test_open_and_non_manifold_meshes_hold_their_measured_accuracy(renderer: penumbra.Renderer, truth: dict[str, np.ndarray], mesh: str, radius: float, config: str) -> None:
    scene = penumbra.scenes.from_mesh(str(MESHES / mesh), width=SIZE, height=SIZE, light_radius=radius, setup="close")
    name = f"{mesh} close r={radius}"
    gt = truth_of(truth, name, scene)
    hard = renderer.render(scene, "hard")
    method, params = CONFIGS[config]
    bounds = {
        "rmse": min(RATIO_TO_HARD * metrics.rmse(hard.visibility, gt, metrics.penumbra_region(gt)), 1.15 * OPEN_MEASURED[(mesh, radius)][config] + 0.005),
        "stray_percent": STRAY_PERCENT,
        "volume_ratio": VOLUME_RATIO[method],
    }
    check_against_truth(f"{name} {config}", renderer.render(scene, method, **params), gt, bounds)


@pytest.mark.parametrize("method, levels", [("pvm", ["none", "cone", "cone+hidden", "cone+hidden+centre", "all"]), ("pvmf", ["none", "hidden", "hidden+horizon", "all"])])
def test_every_repair_level_is_in_the_pass_keys(method: str, levels: list[str], loaded: dict[str, penumbra.Scene]) -> None:
    """Each level of `repairs` after another through a renderer with the pass
    cache gives the image of a renderer without it (a pass keyed without the
    repairs it reads would be reused stale), and every level changes the
    picture on this real mesh."""
    scene = penumbra.scenes.from_mesh(str(MESHES / "spot.obj"), width=64, height=64, setup="close")
    cached, fresh = penumbra.Renderer(pass_cache=True), penumbra.Renderer(pass_cache=False)
    images = []
    for level in levels + levels[::-1]:
        got = cached.render(scene, method, repairs=level, map_size=1024)
        expected = fresh.render(scene, method, repairs=level, map_size=1024)
        np.testing.assert_array_equal(got.visibility, expected.visibility, err_msg=f"{method} repairs={level}")
        assert got.params["repairs"] == level
        images.append(expected.visibility)
    for a, b in zip(images[: len(levels)], images[1 : len(levels)]):
        assert not np.array_equal(a, b), method


@pytest.mark.parametrize("name", ["spot.obj close r=0.3", "teapot-mcguire-closed.obj close r=0.3"])
def test_each_pvm_repair_lowers_the_error(renderer: penumbra.Renderer, truth: dict[str, np.ndarray], name: str) -> None:
    """The repairs of docs/real_meshes.md one at a time: each lowers pvm's
    penumbra RMSE on these meshes, and the paper's construction alone
    leaves the streaks issue 15 shows (over 1% of the lit and umbra pixels
    stray; 0.02% at most with every repair). Measured with edges="two"
    and no map bound (benchmarks/real_meshes.toml's rows "edges=two
    map_samples=0 repairs=..."): on spot 0.317, 0.184, 0.134,
    0.113, 0.066, 10.3% stray pixels without a repair; on the teapot 0.273,
    0.233, 0.173, 0.128, 0.023, 2.3%. With the default edges="chain" the loop walk takes
    part of repair "cone"'s gain on the teapot (the rows "repairs=...":
    none 0.243, cone 0.233), and with the map bound on, repair "centre"'s
    on spot (cone+hidden 0.1040, +centre 0.1037), so the repairs are held on the
    construction they repair."""
    scene = SUITE[name]
    gt = truth_of(truth, name, scene)
    region = metrics.penumbra_region(gt)
    errors, strays = [], []
    for level in ("none", "cone", "cone+hidden", "cone+hidden+centre", "all"):
        result = renderer.render(scene, "pvm", repairs=level, edges="two", map_samples=0)
        errors.append(metrics.rmse(result.visibility, gt, region))
        stray, out_of = metrics.stray_pixels(result.visibility, gt, result.object_id >= 0)
        strays.append(100.0 * stray / out_of)
    assert all(a > 1.05 * b for a, b in zip(errors, errors[1:])), errors
    assert strays[0] > 1.0 and strays[-1] < 0.1, strays


def test_pvmf_repairs_tighten_the_mask_and_keep_the_horizon(renderer: penumbra.Renderer, truth: dict[str, np.ndarray]) -> None:
    """pvmf (its defaults) on the teapot: leaving out the edges hidden
    from the light's centre masks fewer pixels (measured 297 to 257 against
    124 true penumbra pixels) at the same error; the horizon then cuts the
    error by more than half (0.13 to 0.039: the teapot's terminator, lit from
    part of the light only)."""
    name = "teapot-mcguire-closed.obj close r=0.3"
    scene = SUITE[name]
    gt = truth_of(truth, name, scene)
    region = metrics.penumbra_region(gt)
    results = {level: renderer.render(scene, "pvmf", repairs=level) for level in ("none", "hidden", "hidden+horizon")}
    error = {level: metrics.rmse(r.visibility, gt, region) for level, r in results.items()}
    assert results["hidden"].stats["masked_pixels"] < 0.95 * results["none"].stats["masked_pixels"]
    assert results["hidden"].stats["hidden_silhouette_edges"] > 0 == results["none"].stats["hidden_silhouette_edges"]
    assert abs(error["hidden"] - error["none"]) < 0.01, error
    assert error["hidden+horizon"] < 0.5 * error["hidden"], error

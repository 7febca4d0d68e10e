"""`penumbra bench`: the config, the Pareto and equal-error arithmetic, and
the quick run end to end (the CI run of the benchmark)."""

from __future__ import annotations

import contextlib
import csv
import io
import math
from pathlib import Path

import numpy as np
import pytest

import penumbra.grid
from penumbra import bench, cli, metrics
from penumbra import mitsuba as pm
from penumbra.sweep import grid
from penumbra.errors import ParameterError

CONFIG = Path(__file__).resolve().parents[1] / "benchmarks" / "bench.toml"


def test_pareto_front_keeps_only_unbeaten_points_sorted_by_time() -> None:
    points = [(10.0, 0.5), (1.0, 0.9), (5.0, 0.2), (7.0, 0.3), (5.0, 0.25), (20.0, 0.1), (30.0, 0.1)]
    assert bench.pareto_front(points) == [1, 2, 5]
    assert bench.pareto_front([]) == []


def test_time_at_error_interpolates_log_log_and_marks_bounds() -> None:
    # A peer whose error halves when its time quadruples: e = 0.4 (t / 1)^-0.5.
    curve = [(1.0, 0.4), (4.0, 0.2), (16.0, 0.1), (8.0, 0.3)]  # (8, 0.3) is off the front
    t, bound = bench.time_at_error(curve, 0.2 / math.sqrt(2))
    assert bound == "=" and t == pytest.approx(8.0)
    assert bench.time_at_error(curve, 0.2) == (pytest.approx(4.0), "=")
    assert bench.time_at_error(curve, 0.5) == (1.0, "<=")
    assert bench.time_at_error(curve, 0.05) == (16.0, ">=")
    assert math.isnan(bench.time_at_error([], 0.1)[0])


def test_grids_expand_to_their_product_without_repeats() -> None:
    grids = [{"a": [1, 2], "b": "x"}, {}, {"a": 1, "b": "x"}]
    assert bench.expand(grids) == [{"a": 1, "b": "x"}, {"a": 2, "b": "x"}, {}]
    # One expander for bench and sweep: the same sets, bench dropping repeats.
    assert bench.expand(grids) == penumbra.grid.expand(grids, unique=True)
    assert penumbra.grid.expand(grids) == grid(grids)
    assert bench.label({}) == "default"
    assert bench.label({"n_blur": 0, "kernel": "disk"}) == "kernel=disk n_blur=0"


def test_the_repository_config_loads_full_and_quick() -> None:
    import penumbra

    if penumbra.scenes.meshes_folder() is None:
        pytest.skip("the config's real scenes need the shared meshes")
    full = bench.load_config(CONFIG)
    quick = bench.load_config(CONFIG, quick=True)
    assert full.name == "bench" and quick.name == "bench_quick"
    real = [s for s in full.scenes if s not in penumbra.scenes.names()]
    assert len([s for s in real if s.startswith("generated:")]) >= 20 and len(real) >= 24, "the full run is on real scenes"
    assert full.large["width"] == 1920 and full.large["height"] == 1080 and full.large["scenes"]
    assert quick.scenes == ["sphere_on_plane", "generated:6"]
    assert quick.size < full.size and quick.peers["mitsuba_spp"] and quick.peers["reference_samples"]

    assert set(full.methods) == set(penumbra.methods()) - {"reference", "adaptive"}, "every method but the peer (and adaptive, too slow for the full run) is benchmarked"


def test_a_visibility_only_config_times_renders_without_shading(tmp_path: Path) -> None:
    from penumbra.bench.runner import render_outputs

    path = tmp_path / "c.toml"
    path.write_text("scenes = ['sphere_on_plane']\nradiance = false\n")
    assert render_outputs(bench.load_config(path)) == ["visibility", "object_id"]
    assert "radiance" in render_outputs(bench.load_config(path, overrides=["radiance=true"]))
    # A config's own columns may read any image.
    columns = bench.load_config(path, overrides=["columns=['penumbra.metrics:compare']"])
    assert {"radiance", "position", "normal"} <= set(render_outputs(columns))


def test_set_replaces_top_level_keys(tmp_path: Path) -> None:
    path = tmp_path / "c.toml"
    path.write_text("scenes = ['sphere_on_plane']\nsize = 64\n[large]\nscenes = ['sphere_on_plane']\nwidth = 8\nheight = 8\n")
    cfg = bench.load_config(path, overrides=["scenes = ['cube_on_plane', 'resting_box']", "size=16", "large={}"])
    assert cfg.scenes == ["cube_on_plane", "resting_box"] and cfg.size == 16 and not cfg.large
    with pytest.raises(ParameterError, match="unknown key 'sizes'"):
        bench.load_config(path, overrides=["sizes=3"])
    with pytest.raises(ParameterError, match="--set takes key=<TOML value>"):
        bench.load_config(path, overrides=["scenes=[cube"])


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("scenes = ['sphere_on_plane']\nsize = 0\n", "'size' must be at least 1"),
        ("scenes = ['sphere_on_plane']\nsizes = 3\n", "unknown key 'sizes'"),
        ("scenes = 'sphere_on_plane'\n", "'scenes' must be a list"),
        ("scenes = ['no_such_scene']\n", "unknown scenes ['no_such_scene']"),
        ("scenes = ['generated:5..2']\n", "unknown scenes ['generated:5..2']"),
        ("scenes = ['sphere_on_plane']\n[large]\nscenes = ['sphere_on_plane']\nwidth = 64\n", "[large] needs 'height'"),
        ("scenes = ['sphere_on_plane']\n[large]\nscenes = ['sphere_on_plane']\nwidth = 64\nheight = 0\n", "'height' must be an integer of at least 1"),
        ("scenes = ['sphere_on_plane']\n[methods]\nhard = 3\n", "methods.hard must be a table"),
        ("scenes = [\n", "not valid TOML"),
        ("scenes = ['sphere_on_plane']\n[quick]\nrepeats = 'two'\n", "[quick]: 'repeats' must be an integer"),
        # Scene tables (variants).
        ("scenes = [{ light_radius = 0.1 }]\n", "a scene table takes 'scene'"),
        ("scenes = [{ scene = 'cube_on_plane', radius = 0.1 }]\n", "a scene table takes 'scene'"),
        ("scenes = [{ scene = 'cube_on_plane', light_radius = -1 }]\n", "'light_radius' must be a number of at least 0"),
        ("scenes = [{ scene = 'cube_on_plane', setup = 'close' }]\n", "places 'mesh:<file>' scenes only"),
        ("scenes = [{ scene = 'cube_on_plane', light_radius = [0.1, 0.2], label = 'x' }]\n", "'label' names one scene"),
        ("scenes = [{ scene = 'no_such_scene' }]\n", "unknown scenes"),
        ("scenes = ['sphere_on_plane']\ntable = [1]\n", "'table' must be a list of results.csv column names"),
        ("scenes = [{ scene = 'cube_on_plane', form = 'soup' }]\n", "reshapes the mesh of a scene with a 'setup'"),
        ("scenes = ['sphere_on_plane']\n[against.pcss]\nhard = { method = 'hard', keep = 'map_size' }\n", "[against.pcss] maps names to tables"),
        ("scenes = [{ scene = 'resting_box', camera = { eye = [0, 9, 0] } }]\n", "a scene's 'camera' takes 'eye', 'target'"),
        ("scenes = ['sphere_on_plane']\ncolumns = ['no_function']\n", "'columns' must be a list of \"module:function\" names"),
        ("scenes = ['sphere_on_plane']\nresolution_error = 1\n", "'resolution_error' is a factor of the map size of at least 2"),
        ("scenes = ['sphere_on_plane']\nsampling_noise = 1\n", "'sampling_noise' must be true or false"),
        ("scenes = ['sphere_on_plane']\n[time_to_error]\nerrors = [0.1]\naggregate = 'max'\n", "[time_to_error] takes 'errors'"),
        ("scenes = ['sphere_on_plane']\n[large]\nscenes = ['sphere_on_plane']\nwidth = 8\nheight = 8\nresolution_error = -2\n", "[large]: 'resolution_error'"),
    ],
)
def test_bad_configs_name_the_problem(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "c.toml"
    path.write_text(text)
    with pytest.raises(ParameterError, match=message.replace("[", r"\[").replace("]", r"\]")):
        bench.load_config(path, quick=True)


def test_scene_tables_expand_to_labelled_variants(tmp_path: Path) -> None:
    import penumbra

    path = tmp_path / "v.toml"
    path.write_text(
        "scenes = ['sphere_on_plane', { scene = 'cube_on_plane', light_radius = [0.1, 0.4] }, 'wide_floor',"
        " { scene = 'resting_box', light_radius = 0.2, label = 'box' }]\n"
        "table = ['visibility_rmse_penumbra']\n[large]\nscenes = ['cube_on_plane r=0.4']\nwidth = 16\nheight = 8\n"
    )
    cfg = bench.load_config(path)
    assert cfg.scenes == ["sphere_on_plane", "cube_on_plane r=0.1", "cube_on_plane r=0.4", "wide_floor", "box"]
    assert cfg.large["scenes"] == ["cube_on_plane r=0.4"], "a [large] part names the main part's variants by label"
    assert cfg.table == ["visibility_rmse_penumbra"]
    swept = cfg.scene("cube_on_plane r=0.4", 16, 8)
    plain = penumbra.scenes.get("cube_on_plane", width=16, height=8)
    assert swept.light.radius == pytest.approx(0.4) and swept.name == "cube_on_plane r=0.4"
    assert swept.light.intensity.tolist() == plain.light.intensity.tolist(), "the same light, another radius"
    assert cfg.scene("sphere_on_plane", 16, 8).camera.width == 16
    assert cfg.scene("wide_floor", 16, 8).meshes[1].name == "box", "the wide floor's own box caster"


def test_mesh_variants_are_the_real_mesh_suites_scenes() -> None:
    import penumbra

    root = penumbra.scenes.meshes_folder()
    if root is None:
        pytest.skip("needs the shared meshes")
    variant = bench.SceneVariant("mesh:spot.obj", 0.3, "wide_floor", "spot")
    suite = penumbra.scenes.real_mesh_suite(str(root), width=24, height=24, meshes=("spot.obj",))["spot.obj wide_floor r=0.3"]
    built = variant.build(24, 24)
    # The ground truth's cache key: the same scene hashes the same, so its cached truth is reused.
    assert pm._scene_key(built, built.camera).hexdigest() == pm._scene_key(suite, suite.camera).hexdigest()
    assert built.name == "spot"


def test_a_scene_without_a_penumbra_leaves_the_medians_and_the_plot_alone(tmp_path: Path) -> None:
    # A light of radius 0 (pvmf_cost.toml's first radius): no penumbra, a NaN penumbra RMSE.
    rows = [
        {"scene": f"s r={r}", "method": m, "label": "default", "kind": "method", "total_ms": ms, "time_over_hard": ms / 2.0, bench.ERROR: e}
        for r, e in ((0, math.nan), (0.1, 0.2), (0.5, 0.1))
        for m, ms in (("hard", 2.0), ("pvmf", 6.0))
    ]
    rows.append({"scene": "s r=0", "method": "wedges", "label": "default", "kind": "method", "total_ms": 3.0, "time_over_hard": 1.5, bench.ERROR: math.nan})
    points = {p.method: p for p in bench.aggregate(rows)}
    assert points["hard"].error == pytest.approx(0.15) and points["pvmf"].ms == 6.0
    assert math.isnan(points["wedges"].error)
    bench.plot_pareto(list(points.values()), tmp_path / "pareto.png", "radius 0")
    assert (tmp_path / "pareto.png").stat().st_size > 0


def test_markdown_table_writes_the_chosen_columns() -> None:
    rows = [
        {"scene": "s", "size": "8x8", "method": "hard", "label": "default", "visibility_rmse_penumbra": 0.123456, "stat_wedges": ""},
        {"scene": "s", "size": "8x8", "method": "wedges", "label": "default", "visibility_rmse_penumbra": 0.05, "stat_wedges": 120.0},
    ]
    text = bench.markdown_table(rows, ["visibility_rmse_penumbra", "stat_wedges"])
    assert text.splitlines() == [
        "| scene | size | method | setting | visibility_rmse_penumbra | stat_wedges |",
        "|---|---|---|---|---|---|",
        "| s | 8x8 | hard | default | 0.1235 |  |",
        "| s | 8x8 | wedges | default | 0.05 | 120 |",
    ]


def test_every_study_config_loads() -> None:
    import penumbra

    if penumbra.scenes.meshes_folder() is None:
        pytest.skip("the studies' real scenes need the shared meshes")
    implemented = set(penumbra.methods())
    for path in sorted(CONFIG.parent.glob("*.toml")):
        cfg = bench.load_config(path)
        assert cfg.scenes and set(cfg.methods) <= implemented, path.name
        for label in cfg.scenes + list(cfg.large.get("scenes", [])):
            assert cfg.scene(label, 8, 8).camera.width == 8, (path.name, label)


def test_a_missing_config_is_a_clear_cli_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["bench", "--config", str(tmp_path / "none.toml")]) == 2
    assert "cannot read the benchmark config" in capsys.readouterr().err


@pytest.mark.gpu
def test_quick_run_writes_every_output_and_its_numbers_hold(renderer: object, tmp_path: Path) -> None:
    if not pm.variant().startswith("llvm"):
        pytest.skip("visibility ground truth needs Mitsuba's llvm variant")
    import penumbra

    if penumbra.scenes.meshes_folder() is None:
        pytest.skip("the quick run's generated scene needs the shared meshes")
    assert cli.main(["bench", "--quick", "--config", str(CONFIG), "--out", str(tmp_path)]) == 0
    for name in ("results.csv", "pareto.png", "pareto.md", "ratios.md", "suite.md", "rows.jsonl", "scaling.csv", "scaling.png", "machine.md"):
        assert (tmp_path / name).stat().st_size > 0, name
    with open(tmp_path / "results.csv") as f:
        rows = list(csv.DictReader(f))
    cfg = bench.load_config(CONFIG, quick=True)
    assert {r["method"] for r in rows} == set(cfg.methods) | {"reference", "mitsuba"}
    assert {r["size"] for r in rows} == {"48x48", "64x36"}, "the main part and the [large] one"
    hard = [r for r in rows if r["method"] == "hard" and r["label"] == "default" and r["scene"] == "sphere_on_plane"]
    assert len(hard) == 1 and float(hard[0]["time_over_hard"]) == 1.0
    # The row schema sweeps share (penumbra.grid.result_columns): ms_<pass>, stat_<name>, reused.
    assert float(hard[0]["ms_gbuffer"]) > 0 and float(hard[0]["stat_map_size"]) > 0 and hard[0]["reused"] == ""
    # radiance = false: the question is visibility, and the timed renders do not shade.
    assert not cfg.radiance and not hard[0].get("ms_shading"), hard[0].get("ms_shading")
    assert not any(k.startswith("time_") and k not in ("time_over_hard", "time_over_mitsuba") for k in rows[0])
    # Every method row is set against the scene's Mitsuba curve at its own error.
    for r in rows:
        if r["method"] != "mitsuba":
            assert r["mitsuba_bound"] in ("=", "<=", ">=") and float(r["time_over_mitsuba"]) > 0, r
    for r in rows:
        assert float(r["total_ms"]) > 0 and 0 <= float(r[bench.ERROR]) < 1, r
        assert float(r["noise_visibility_rmse_penumbra"]) >= 0
    error = {(r["method"], r["label"]): float(r[bench.ERROR]) for r in rows}
    # The peers converge: four times the samples, clearly less error (measured
    # at 48 px: reference 0.118 -> 0.067, Mitsuba 0.157 -> 0.066).
    assert error[("reference", "n_samples=16")] < 0.8 * error[("reference", "n_samples=4")]
    assert error[("mitsuba", "spp=16")] < 0.8 * error[("mitsuba", "spp=4")]
    ratios = (tmp_path / "ratios.md").read_text()
    for method in cfg.methods:
        assert f"| {method} |" in ratios
    assert "time / Mitsuba at equal error" in ratios
    suite = (tmp_path / "suite.md").read_text()
    assert "### 48x48, 2 scenes" in suite and "### 64x36, 1 scenes" in suite and "### What to use" in suite
    # Started again, the run reuses every finished scene.
    capsys = io.StringIO()
    with contextlib.redirect_stdout(capsys):
        assert cli.main(["bench", "--quick", "--config", str(CONFIG), "--out", str(tmp_path)]) == 0
    assert capsys.getvalue().count(": cached") == 3
    machine = (tmp_path / "machine.md").read_text()
    assert "commit:" in machine and "adapter:" in machine
    if penumbra.adapter_info()["is_software"]:
        assert "timing: cpu_clock" in machine and {r["timing_source"] for r in rows} == {"cpu_clock"}


def test_own_noise_is_the_seed_to_seed_rmse_over_sqrt_2_on_the_truths_penumbra() -> None:
    from types import SimpleNamespace

    import numpy as np

    from penumbra import metrics

    truth = np.array([[0.0, 0.5], [1.0, 0.5]])
    gt = SimpleNamespace(images={"visibility": truth, "radiance": np.repeat(truth[..., None], 3, axis=-1)})
    a, b = np.array([[0.0, 0.4], [1.0, 0.6]]), np.array([[0.2, 0.6], [1.0, 0.6]])
    noise = metrics.own_noise((a, b), gt, radiance=(a[..., None] * np.ones(3), b[..., None] * np.ones(3)))
    assert noise["visibility_rmse_penumbra"] == pytest.approx(metrics.rmse(a[:, 1], b[:, 1]) / math.sqrt(2)), "over the truth's penumbra (column 1)"
    assert noise["visibility_rmse"] == pytest.approx(metrics.seed_noise(a, b))
    # Relative to the truth's lit mean (1.0, its one fully lit pixel).
    assert noise["radiance_rmse_rel"] == pytest.approx(noise["visibility_rmse"])
    assert "radiance_rmse_rel" not in metrics.own_noise((a, b), SimpleNamespace(images={"visibility": truth}))


def _rows(scenes_: dict[str, list[tuple[str, dict, float, float]]]) -> list[dict]:
    import json

    return [
        {"scene": s, "size": "8x8", "kind": "peer" if m == "mitsuba" else "method", "method": m, "label": bench.label(p), "params": json.dumps(p),
         "total_ms": ms, "time_over_hard": 1.0, bench.ERROR: e}
        for s, rows in scenes_.items() for m, p, ms, e in rows
    ]


def test_cost_tables_fit_how_the_methods_own_passes_follow_penumbra_and_triangles() -> None:
    rng = np.random.default_rng(3)
    rows = []
    for i in range(12):
        px, tris = float(rng.integers(100, 5000)), float(rng.integers(1000, 100000))
        # Own passes: 0.02 ms per penumbra pixel times sqrt(triangles) / 100;
        # the shared passes (G-buffer, shadow map, readback) are left out.
        own = 0.02 * px * (tris ** 0.5) / 100.0
        rows.append({"scene": f"s{i}", "size": "8x8", "method": "m", "label": "default", "total_ms": own + 50.0,
                     "ms_gbuffer": 10.0, "ms_shadow_map": 30.0, "ms_readback": 10.0, "ms_mask": 0.25 * own, "ms_visibility": 0.75 * own,
                     "penumbra_pixels": px, "stat_triangles": tris})
    rows.append({"scene": "s0", "size": "8x8", "method": "mitsuba", "label": "spp=4", "total_ms": 1.0})
    line = next(l for l in bench.cost_tables(rows).splitlines() if l.startswith("| m |"))
    cells = [c.strip() for c in line.strip("|").split("|")]
    assert cells[2] == "12" and cells[3] == "30.0", cells
    assert (cells[6], cells[7], cells[8]) == ("1.00", "0.50", "1.00"), "the exponents of the cost model, exactly"
    assert cells[9].startswith("visibility ("), "the costliest own pass"
    assert "| mitsuba |" not in bench.cost_tables(rows)
    few = bench.cost_tables(rows[:3])
    assert "| m | default | 3 |" in few and "| - | - | - |" in few, "no fit on fewer than 5 scenes"


def test_halves_tables_say_which_half_of_the_penumbra_holds_the_error() -> None:
    rows = []
    for i, (inner, outer, n_in) in enumerate([(0.2, 0.1, 50.0), (0.1, 0.1, 50.0), (0.3, 0.05, 10.0)]):
        rows.append({"scene": f"s{i}", "size": "8x8", "method": "m", "label": "default", "penumbra_pixels": 100.0,
                     "penumbra_inner_pixels": n_in, "visibility_rmse_inner": inner, "visibility_rmse_outer": outer})
    rows.append({"scene": "s0", "size": "8x8", "method": "old", "label": "default", "penumbra_pixels": 100.0})
    line = next(l for l in bench.halves_tables(rows).splitlines() if l.startswith("| m |"))
    cells = [c.strip() for c in line.strip("|").split("|")]
    # Shares: 50*0.04 / (50*0.04 + 50*0.01) = 0.8; 0.5; 10*0.09 / (10*0.09 + 90*0.0025) = 0.8.
    assert cells[2:] == ["3", "0.2000", "0.1000", "0.80", "2 of 3"], cells
    assert "| old |" not in bench.halves_tables(rows), "rows of a run before the halves are left out"
    assert bench.halves_tables(rows[3:]) == ""


def test_penumbra_halves_split_the_region_at_one_half() -> None:
    gv = np.array([[0.0, 0.01, 0.3, 0.5], [0.7, 0.97, 0.99, 1.0]])
    inner, outer = metrics.penumbra_halves(gv)
    assert inner.tolist() == [[False, False, True, False], [False, False, False, False]]
    assert outer.tolist() == [[False, False, False, True], [True, True, False, False]]
    assert np.array_equal(inner | outer, metrics.penumbra_region(gv)) and not (inner & outer).any()


def test_time_to_error_splits_curves_and_takes_means_or_medians() -> None:
    mitsuba = [("mitsuba", {"spp": 4}, 10.0, 0.4), ("mitsuba", {"spp": 16}, 40.0, 0.1)]
    rows = _rows({
        "a": [("rt", {"adaptive": False, "n": 1}, 5.0, 0.4), ("rt", {"adaptive": False, "n": 4}, 20.0, 0.1), ("rt", {"adaptive": True, "n": 4}, 2.0, 0.1), *mitsuba],
        "b": [("rt", {"adaptive": False, "n": 1}, 15.0, 0.4), ("rt", {"adaptive": False, "n": 4}, 60.0, 0.1), ("rt", {"adaptive": True, "n": 4}, 6.0, 0.3), *mitsuba],
    })
    text = bench.time_to_error_tables(rows, [0.1], "mean", ["adaptive"])
    over = text.split("\n\n")[1].splitlines()
    assert over[0] == "| curve | time to penumbra RMSE 0.1 (ms) | time / Mitsuba's |"
    # Means over the scenes: plain (10, 0.4), (40, 0.1); adaptive (4, 0.2), short of 0.1: a lower bound.
    assert over[2:] == ["| rt adaptive=False | 40.0 | 1.00 |", "| rt adaptive=True | ≥ 4.0 | ~ 0.10 |", "| mitsuba | 40.0 | 1.00 |"]
    assert text.startswith("Means over the scenes:") and "\na:\n" in text and "\nb:\n" in text
    assert "| rt adaptive=True | ≤ 2.0 | ~ 0.05 |" in text.split("\nb:\n")[0], "per scene: on a, adaptive beats 0.1 at its cheapest point"
    assert "| rt |" in bench.time_to_error_tables(rows, [0.1]), "no split: one curve per method"
    assert bench.time_to_error_tables(rows, [0.1]).startswith("Medians over the scenes:")


def test_report_rewrites_the_tables_from_results_csv_without_rendering(tmp_path: Path) -> None:
    (tmp_path / "c.toml").write_text(
        "scenes = ['sphere_on_plane']\nsize = 8\ntable = ['total_ms']\n[methods]\nhard = [{}]\n"
        "[time_to_error]\nerrors = [0.2]\naggregate = 'mean'\n"
    )
    rows = _rows({"sphere_on_plane": [("hard", {}, 2.0, 0.3), ("mitsuba", {"spp": 4}, 1.0, 0.4), ("mitsuba", {"spp": 16}, 4.0, 0.1)]})
    bench.write_csv(tmp_path / "results.csv", rows)
    assert bench.read_csv(tmp_path / "results.csv")[0]["total_ms"] == 2.0, "numbers come back as numbers"
    assert cli.main(["bench", "--config", str(tmp_path / "c.toml"), "--out", str(tmp_path), "--report"]) == 0
    for name in ("suite.md", "pareto.md", "ratios.md", "cost.md", "table.md", "time_to_error.md", "pareto.png"):
        assert (tmp_path / name).stat().st_size > 0, name
    assert "| hard | ≥ 2.0 | ~ 1.00 |\n| mitsuba | 2.0 | 1.00 |" in (tmp_path / "time_to_error.md").read_text(), "Mitsuba at 0.2: halfway, log-log"
    assert not (tmp_path / "machine.md").exists(), "nothing rendered"
    with pytest.raises(ParameterError, match="does not exist: run the benchmark first"):
        bench.run_from_args(bench.build_parser(__import__("argparse").ArgumentParser()).parse_args(
            ["--config", str(tmp_path / "c.toml"), "--out", str(tmp_path / "none"), "--report"]))


def test_a_form_or_a_camera_variant_is_the_scene_in_that_form_or_from_there(tmp_path: Path) -> None:
    import penumbra

    if penumbra.scenes.meshes_folder() is None:
        pytest.skip("needs the shared meshes")
    welded, soup = bench.SceneVariant("mesh:cube.obj", 0.45, "default", "cube"), bench.SceneVariant("mesh:cube.obj", 0.45, "default", "cube soup", "soup")
    built = soup.build(8, 8)
    assert len(built.meshes[1].vertices) == 3 * len(built.meshes[1].faces) == 3 * len(welded.build(8, 8).meshes[1].faces), "every face its own corners"
    (tmp_path / "c.toml").write_text("scenes = [{ scene = 'resting_box', label = 'above', camera = { eye = [0, 9, 0], target = [0, 0, 0], up = [0, 0, -1] } }]\n")
    above = bench.load_config(tmp_path / "c.toml").scene("above", 16, 8)
    assert above.camera.eye == (0.0, 9.0, 0.0) and above.camera.width == 16 and above.name == "above"


def _pixel_columns(result: object, scene: object) -> dict[str, float]:
    """A config's own column (``columns``): it gets every image."""
    return {"position_pixels": float(result.position.shape[0] * result.position.shape[1]), "same_scene": float(scene.camera.width == 24)}  # type: ignore[attr-defined]


@pytest.mark.gpu
def test_rows_carry_their_own_noise_and_resolution_error(renderer: object, tmp_path: Path) -> None:
    if not pm.variant().startswith("llvm"):
        pytest.skip("visibility ground truth needs Mitsuba's llvm variant")
    (tmp_path / "c.toml").write_text(
        "scenes = ['sphere_on_plane']\nsize = 24\nground_truth_spp = 16\nradiance = false\nwarmup = 0\nrepeats = 1\n"
        "sampling_noise = true\nresolution_error = 2\ncolumns = ['test_bench:_pixel_columns']\n[methods]\npcss = [{ map_size = 256 }]\nhard = [{}, { map_size = 256 }]\n"
        "[peers]\nmitsuba_spp = [4]\n[against.pcss]\nhard = { method = 'hard', keep = ['map_size'], threshold = 0.1 }\n"
        "itself = {}\n[against.'*']\nfiner = { set = { map_size = 512 }, when = { map_size = 256 } }\nseed = { set = { seed = 1 } }\n"
    )
    rows = {(r["method"], r["label"]): r for r in bench.run(bench.load_config(tmp_path / "c.toml"), tmp_path, log=lambda _: None)}
    pcss = rows[("pcss", "map_size=256")]
    # Against a row of the run (hard at the same map size): its image and its time.
    assert 0 < pcss["vs_hard_mean"] <= pcss["vs_hard_max"] <= 1 and pcss["vs_hard_over"] >= 1
    assert pcss["vs_hard_time"] == pytest.approx(pcss["total_ms"] / rows[("hard", "map_size=256")]["total_ms"])
    # Against a configuration rendered for the purpose: no time; against itself: nothing.
    assert 0 < pcss["vs_finer_rmse"] and "vs_finer_time" not in pcss and not any(k.startswith("vs_itself") for k in pcss)
    # '*': every method, the rows 'when' names, the methods that take the parameters set.
    assert "vs_finer_max" in rows[("hard", "map_size=256")] and "vs_finer_max" not in rows[("hard", "default")]
    assert pcss["position_pixels"] == 24 * 24 and pcss["same_scene"] == 1.0, "the columns' function saw positions and the scene"
    assert "vs_seed_max" in pcss and not any(k.startswith("vs_seed") for k in rows[("hard", "map_size=256")]), "hard takes no seed"
    rows = {m: r for (m, lab), r in rows.items() if lab in ("default", "map_size=256", "spp=4")}
    assert "sampling_noise_visibility_rmse" not in rows["hard"], "hard has no seed"
    assert rows["hard"]["resolution_error_visibility_rmse"] >= 0 and "resolution_error_visibility_rmse" not in rows["mitsuba"]
    assert 0 < rows["pcss"]["sampling_noise_visibility_rmse_penumbra"] < 0.5 and 0 < rows["pcss"]["resolution_error_visibility_rmse_penumbra"] < 0.5
    assert 0 < rows["mitsuba"]["sampling_noise_visibility_rmse_penumbra"] < 0.5, "Mitsuba's own noise at 4 spp"

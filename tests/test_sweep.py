"""penumbra.sweep (issue 9): grids, the DataFrame, reuse, ground truth,
executors and the progress bar."""

from __future__ import annotations

import concurrent.futures
import math
import multiprocessing
import os
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import penumbra
import penumbra.mitsuba as pm
from penumbra.sweep import grid

SIZE = 32
MAP = 128


def scene(**kw: float) -> penumbra.Scene:
    return penumbra.scenes.get("cube_on_plane", width=SIZE, height=SIZE, **kw)


def test_grid_is_the_product_with_the_last_key_fastest() -> None:
    assert grid({"a": [1, 2], "b": ["x", "y"]}) == [{"a": 1, "b": "x"}, {"a": 1, "b": "y"}, {"a": 2, "b": "x"}, {"a": 2, "b": "y"}]
    assert grid([{"a": 1}, {"b": 2}]) == [{"a": 1}, {"b": 2}]
    assert grid(None) == [{}]
    # The expander bench uses too: a value that is not a list is one value,
    # and each dict of a list is a grid; repeated sets stay (one row each).
    assert grid({"a": 3, "b": "xy"}) == [{"a": 3, "b": "xy"}]
    assert grid([{"a": [1, 2]}, {"a": 1}]) == [{"a": 1}, {"a": 2}, {"a": 1}]
    with pytest.raises(penumbra.ParameterError, match="params must be"):
        grid(5)  # type: ignore[arg-type]


def test_sweep_rows_columns_and_reuse(renderer: penumbra.Renderer) -> None:
    renderer.clear_pass_cache()
    s = scene()
    df = penumbra.sweep(s, "pvmf", {"map_size": [MAP], "n_blur": [0, 4, 8]}, renderer=renderer, keep_images=True, progress=False)
    assert isinstance(df, pd.DataFrame) and len(df) == 3
    assert list(df["config"]) == [0, 1, 2] and set(df["method"]) == {"pvmf"} and set(df["scene"]) == {"scene"}
    assert list(df["n_blur"]) == [0, 4, 8] and list(df["map_size"]) == [MAP] * 3
    # The first configuration runs every pass; the others reuse all but the blur.
    assert df["stat_reused_passes"].tolist() == [0, 5, 5]
    assert df["reused"].tolist() == ["", "estimation,gbuffer,mask,shadow_map,solid_layers", "estimation,gbuffer,mask,shadow_map,solid_layers"]
    assert not math.isnan(df["ms_mask"][0]) and df["ms_mask"][1:].isna().all()
    assert (df["total_ms"] > 0).all() and (df["worker_pid"] == os.getpid()).all()
    for row in df.itertuples():
        direct = renderer.render(s, "pvmf", map_size=MAP, n_blur=row.n_blur)
        np.testing.assert_array_equal(row.images["visibility"], direct.visibility)
        assert sorted(row.images) == ["radiance", "visibility"]


def test_several_scenes_and_methods_and_effective_parameters(renderer: penumbra.Renderer) -> None:
    scenes = {"small": scene(light_radius=0.2), "large": scene(light_radius=0.8)}
    df = penumbra.sweep(scenes, ["hard", "pvm"], [{"map_size": MAP}, {"map_size": MAP, "bias": "midpoint"}], renderer=renderer, progress=False)
    assert list(zip(df["scene"], df["method"])) == [(s, m) for s in scenes for m in ["hard", "pvm"] for _ in range(2)]
    # Parameter columns hold the value in effect, defaults included.
    assert df["bias"].tolist() == ["slope", "midpoint"] * 4
    assert "images" not in df


def test_ground_truth_adds_every_metric(renderer: penumbra.Renderer, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PENUMBRA_CACHE_DIR", str(tmp_path))
    s = scene()
    df = penumbra.sweep(s, ["hard", "pvmf"], {"map_size": [MAP]}, ground_truth=True, ground_truth_spp=4, renderer=renderer, progress=False)
    gt = pm.ground_truth(s, spp=4)
    assert all(gt.cached.values()), "the sweep's ground truth is in the cache"
    expected = penumbra.metrics.compare(renderer.render(s, "pvmf", map_size=MAP), gt)
    row = df[df["method"] == "pvmf"].iloc[0]
    for key, value in expected.items():
        assert row[key] == pytest.approx(value, nan_ok=True), key
    # A GroundTruth object, or a dict by scene name, gives the same.
    again = penumbra.sweep({"cube": s}, "pvmf", {"map_size": [MAP]}, ground_truth={"cube": gt}, renderer=renderer, progress=False)
    assert again["visibility_rmse_penumbra"][0] == row["visibility_rmse_penumbra"]
    with pytest.raises(penumbra.ParameterError, match="no ground truth"):
        penumbra.sweep({"a": s, "b": s}, "hard", ground_truth={"a": gt}, renderer=renderer, progress=False)


@pytest.mark.gpu
def test_process_pool_matches_in_process(renderer: penumbra.Renderer) -> None:
    s = scene()
    params = {"map_size": [MAP], "n_blur": [0, 2, 4, 8]}
    here = penumbra.sweep(s, "pvmf", params, renderer=renderer, keep_images=["visibility"], progress=False)
    # spawn: a forked child would inherit the parent's Vulkan device threads.
    with concurrent.futures.ProcessPoolExecutor(max_workers=2, mp_context=multiprocessing.get_context("spawn")) as pool:
        there = penumbra.sweep(s, "pvmf", params, executor=pool, keep_images=["visibility"], progress=False)
    assert list(there["config"]) == list(here["config"]) and list(there["n_blur"]) == [0, 2, 4, 8]
    assert (there["worker_pid"] != os.getpid()).all()
    for a, b in zip(here["images"], there["images"]):
        np.testing.assert_array_equal(a["visibility"], b["visibility"])
    # Chunks are contiguous, so a worker's second configuration reuses its first's passes.
    assert there["stat_reused_passes"].sum() > 0
    with concurrent.futures.ThreadPoolExecutor(max_workers=2) as threads:
        threaded = penumbra.sweep(s, "pvmf", params, executor=threads, chunksize=1, keep_images=["visibility"], progress=False)
    for a, b in zip(here["images"], threaded["images"]):
        np.testing.assert_array_equal(a["visibility"], b["visibility"])
    with pytest.raises(penumbra.ParameterError, match="renderer="):
        penumbra.sweep(s, "hard", executor=concurrent.futures.ThreadPoolExecutor(1), renderer=renderer)


def test_progress_bar(renderer: penumbra.Renderer, capsys: pytest.CaptureFixture[str]) -> None:
    s = scene()
    penumbra.sweep(s, "hard", {"map_size": [MAP, MAP // 2]}, renderer=renderer)
    assert "sweep" not in capsys.readouterr().err, "no bar when stderr is not a terminal"
    penumbra.sweep(s, "hard", {"map_size": [MAP, MAP // 2]}, renderer=renderer, progress=True)
    assert "2/2" in capsys.readouterr().err


def test_bad_input() -> None:
    with pytest.raises(penumbra.SceneError):
        penumbra.sweep([], "hard")
    with pytest.raises(penumbra.SceneError):
        penumbra.sweep({"x": "not a scene"}, "hard")  # type: ignore[dict-item]
    with pytest.raises(penumbra.ParameterError):
        penumbra.sweep(scene(), [])

"""penumbra.sweep on a Dask cluster (issue 33): a LocalCluster of two worker
processes renders the same sweep as the in-process one, bit for bit, with the
ground truth rendered once and scattered, progress as chunks come back, and a
worker's failure naming its configuration.

Each worker process imports penumbra itself: the workers inherit this
process's environment (PYTHONPATH, XDG_RUNTIME_DIR, PENUMBRA_CACHE_DIR), so
they import the same package as the test."""

from __future__ import annotations

import logging
import os
import warnings
from collections.abc import Iterator
from typing import Any

import numpy as np
import pandas as pd
import pytest

import penumbra

distributed = pytest.importorskip(
    "distributed", reason="Dask distributed is not installed: pip install 'penumbra[cluster]' (scripts/setup.sh installs it)"
)

SIZE = 32
METHODS = ["hard", "pcf", "pcss"]
#: 2 scenes x 3 methods x 2 map sizes: 12 configurations.
PARAMS = {"map_size": [64, 128]}
#: Columns that differ between runs by design: times, the worker, and the
#: counts of work done in the call, which the caches decide (the in-process
#: renderer's caches are warm from other tests).
VARYING = ("total_ms", "timing_source", "worker_pid", "reused", "images", "stat_shadow_maps_rendered", "stat_silhouette_cache_hits")


def scenes() -> dict[str, penumbra.Scene]:
    return {
        "cube": penumbra.scenes.get("cube_on_plane", width=SIZE, height=SIZE, light_radius=0.4),
        "casters": penumbra.scenes.get("overlapping_casters", width=SIZE, height=SIZE),
    }


@pytest.fixture(scope="module")
def client() -> Iterator[Any]:
    try:
        penumbra.adapter_info()
    except penumbra.GpuUnavailableError as e:
        pytest.skip(f"no GPU adapter: {e}")
    with warnings.catch_warnings():
        # The cluster's own start-up warnings (a dashboard port in use) are not the test's.
        warnings.simplefilter("ignore")
        cluster = distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0", silence_logs=logging.ERROR
        )
        client = distributed.Client(cluster)
    try:
        yield client
    finally:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            client.close()
            cluster.close()


def fixed_columns(df: pd.DataFrame) -> pd.DataFrame:
    keep = [c for c in df.columns if c not in VARYING and not c.startswith("ms_") and not c.startswith("stat_reused")]
    return df[keep]


def test_dask_sweep_matches_in_process(client: Any, renderer: penumbra.Renderer, capsys: pytest.CaptureFixture[str]) -> None:
    from penumbra.sweep import _worker_count

    assert _worker_count(client, client) == 2, "two worker processes of one thread each"
    truth = "raytraced" if penumbra.adapter_info().get("ray_queries") else None
    kw: dict[str, Any] = {"ground_truth": truth, "ground_truth_spp": 16, "keep_images": ["visibility"]}
    here = penumbra.sweep(scenes(), METHODS, PARAMS, renderer=renderer, progress=False, **kw)
    assert len(here) == 12
    for executor in (client, client.get_executor()):
        there = penumbra.sweep(scenes(), METHODS, PARAMS, executor=executor, progress=True, **kw)
        assert "12/12" in capsys.readouterr().err, "the bar advances as chunks come back"
        assert (there["worker_pid"] != os.getpid()).all()
        assert there["worker_pid"].nunique() <= 2
        pd.testing.assert_frame_equal(fixed_columns(there), fixed_columns(here), check_exact=True)
        for a, b, row in zip(here["images"], there["images"], here.itertuples()):
            assert np.array_equal(a["visibility"], b["visibility"]), f"configuration {row.config} differs"
        # Contiguous chunks (3 configurations each) on one renderer per worker:
        # a chunk's second and third configurations reuse its first's G-buffer.
        assert there["stat_reused_passes"].sum() > 0
    if truth is not None:
        assert "visibility_rmse_penumbra" in here and here["visibility_rmse_penumbra"].notna().all()


def test_a_workers_failure_names_its_configuration(client: Any) -> None:
    # map_size 8 is below the range: the worker's render of configuration 2 refuses it.
    params = [{"map_size": 64}, {"map_size": 128}, {"map_size": 8, "bias": "midpoint"}, {"map_size": 64}]
    with pytest.raises(
        penumbra.ParameterError,
        match=r"map_size.*got int 8; in sweep configuration 2 \(scene 'cube', method 'pcf', map_size=8, bias='midpoint'\) on .+ pid \d+",
    ) as raised:
        penumbra.sweep({"cube": scenes()["cube"]}, "pcf", params, executor=client, chunksize=1, progress=False)
    assert raised.value.sweep_config == {"config": 2, "scene": "cube", "method": "pcf", "params": {"map_size": 8, "bias": "midpoint"}}

"""A sweep in one process against the same sweep on a local Dask cluster of
two worker processes (issue 33; needs `pip install "penumbra[cluster]"`).

The sweep is tests/test_cluster.py's: 2 scenes x pcss, pcf, hard x 2 map
sizes (12 configurations) with a raytraced ground truth of each scene, at
`--size` pixels. Each is run twice: the first run includes building
pipelines (in-process: this process's renderer; on Dask: each worker's),
the second reuses them. The cluster's start-up is timed apart. Prints wall
clock seconds.

    python benchmarks/cluster_sweep.py --size 32
    python benchmarks/cluster_sweep.py --size 256
"""

from __future__ import annotations

import argparse
import logging
import time
import warnings
from typing import Any

import penumbra


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=32, help="image side in pixels (default 32)")
    parser.add_argument("--workers", type=int, default=2, help="Dask worker processes, one thread each (default 2)")
    args = parser.parse_args()
    import distributed

    scenes = {
        "cube": penumbra.scenes.get("cube_on_plane", width=args.size, height=args.size, light_radius=0.4),
        "casters": penumbra.scenes.get("overlapping_casters", width=args.size, height=args.size),
    }
    sweep: tuple[Any, ...] = (scenes, ["hard", "pcf", "pcss"], {"map_size": [64, 128]})
    kw: dict[str, Any] = {"ground_truth": "raytraced", "ground_truth_spp": 16, "progress": False}

    def timed(**extra: Any) -> float:
        started = time.perf_counter()
        penumbra.sweep(*sweep, **kw, **extra)
        return time.perf_counter() - started

    serial = [timed(), timed()]
    warnings.simplefilter("ignore")  # the cluster's start-up warnings
    started = time.perf_counter()
    cluster = distributed.LocalCluster(
        n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=":0", silence_logs=logging.ERROR
    )
    client = distributed.Client(cluster)
    start = time.perf_counter() - started
    try:
        dask = [timed(executor=client), timed(executor=client)]
    finally:
        client.close()
        cluster.close()
    print(
        f"{args.size}x{args.size}, 12 configurations and a raytraced truth of each of 2 scenes (16 spp), "
        f"adapter {penumbra.adapter_info()['name']}:\n"
        f"  in-process:        {serial[0]:.2f} s first, {serial[1]:.2f} s again\n"
        f"  {args.workers} Dask workers:    {dask[0]:.2f} s first, {dask[1]:.2f} s again (cluster start {start:.2f} s apart)"
    )


if __name__ == "__main__":
    main()

"""What the pass cache saves in a sweep of a late-stage parameter (issue 9).

Times, in one process, the same renders twice: as a `penumbra.sweep` on a
renderer with the pass cache (the default; cleared before each sweep, so the
first configuration runs every pass), and one by one from scratch on a
renderer built with `pass_cache=False`. Prints the wall-clock time per
configuration of each and their ratio, and checks the images are identical.

    python benchmarks/sweep_cost.py            # the numbers of docs/sweeps.md
    python benchmarks/sweep_cost.py --quick    # small, for a smoke test
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

import numpy as np

import penumbra

SWEEPS: list[tuple[str, str, list[Any]]] = [
    ("pvmf", "n_blur", [0, 2, 4, 6, 8, 12, 16, 24]),
    ("pvm", "falloff", [True, False, True, False, True, False]),
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scene", default="overlapping_casters")
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--map-size", type=int, default=1024)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--quick", action="store_true", help="64 px, 256-texel maps, one repeat")
    args = parser.parse_args()
    if args.quick:
        args.size, args.map_size, args.repeats = 64, 256, 1
    scene = penumbra.scenes.get(args.scene, width=args.size, height=args.size)
    cached = penumbra.Renderer()
    scratch = penumbra.Renderer(pass_cache=False)
    # Warm up both (pipelines, allocator) on another scene, and the sweep's imports (pandas).
    warm = penumbra.scenes.get("sphere_on_plane", width=args.size, height=args.size)
    for r in (cached, scratch):
        for method, _, _ in SWEEPS:
            penumbra.sweep(warm, method, {"map_size": [args.map_size]}, renderer=r, progress=False)
    print(f"{args.scene}, {args.size}x{args.size} pixels, map_size {args.map_size}, "
          f"{cached.adapter_info['name']}; median of {args.repeats}")
    for method, name, values in SWEEPS:
        per_config: dict[str, list[float]] = {"sweep": [], "scratch": []}
        for _ in range(args.repeats):
            cached.clear_pass_cache()
            start = time.perf_counter()
            frame = penumbra.sweep(scene, method, {name: values, "map_size": [args.map_size]}, renderer=cached, keep_images=["visibility"], progress=False)
            per_config["sweep"].append((time.perf_counter() - start) / len(values))
            start = time.perf_counter()
            alone = [scratch.render(scene, method, map_size=args.map_size, **{name: v}) for v in values]
            per_config["scratch"].append((time.perf_counter() - start) / len(values))
            for images, result in zip(frame["images"], alone):
                if not np.array_equal(images["visibility"], result.visibility):
                    raise SystemExit(f"{method} {name}: the cached sweep differs from the renders from scratch")
        reused = int(frame["stat_reused_passes"].sum())
        sweep_ms = statistics.median(per_config["sweep"]) * 1e3
        scratch_ms = statistics.median(per_config["scratch"]) * 1e3
        print(f"{method:5s} {name} over {len(values)} values: sweep {sweep_ms:7.1f} ms/config, "
              f"from scratch {scratch_ms:7.1f} ms/config, ratio {scratch_ms / sweep_ms:4.2f}x "
              f"({reused} passes reused, images identical)")


if __name__ == "__main__":
    main()

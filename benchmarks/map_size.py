"""map_size="auto" against maps of 2048: the size chosen, each method's
penumbra RMSE against Mitsuba at both, the ground truth's noise, and the
time ratio, on every built-in scene, the wide floor, the Cornell box and the
real-mesh suite (issue 24; docs/scaling.md).

    python3 benchmarks/map_size.py [--size 128] [--methods hard pcf pcss pvm pvmf]

Ground truth: Mitsuba at 1024 spp, cached like `penumbra compare`'s; its
noise is the RMSE of a second seed against the first over the penumbra. A
method's auto error passes when it is at most its 2048 error plus that noise.
Times are medians of 3 warm renders of each size, alternating, in this one
run, without the pass cache.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

import numpy as np

import penumbra
from penumbra import metrics
from penumbra import mitsuba as pm

MESHES = Path(__file__).resolve().parents[1] / ".." / "shared" / "meshes"


def scenes(size: int, real: bool) -> dict[str, penumbra.Scene]:
    out = {name: penumbra.scenes.get(name, width=size, height=size) for name in penumbra.scenes.names()}
    out["wide_floor"] = penumbra.scenes.wide_floor(width=size, height=size)
    if real and MESHES.is_dir():
        out["cornell_box"] = penumbra.scenes.cornell_box(str(MESHES / "CornellBox-Original.obj"), width=size, height=size)
        out.update(penumbra.scenes.real_mesh_suite(str(MESHES), width=size, height=size))
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--size", type=int, default=128)
    parser.add_argument("--methods", nargs="+", default=["hard", "pcf", "pcss", "pvm", "pvmf"])
    parser.add_argument("--spp", type=int, default=1024)
    parser.add_argument("--no-real", action="store_true", help="built-in scenes only")
    args = parser.parse_args(argv)
    r = penumbra.Renderer(pass_cache=False)
    print(f"{args.size}x{args.size}; ground truth Mitsuba {args.spp} spp; adapter {r.adapter_info['name']}")
    print("| scene | method | auto size | RMSE auto | RMSE 2048 | GT noise | auto - 2048 <= noise | time auto / 2048 |")
    print("|---|---|---|---|---|---|---|---|")
    worst = -1.0
    ratios = []
    for name, scene in scenes(args.size, not args.no_real).items():
        gt = pm.ground_truth(scene, spp=args.spp, kinds=("visibility",), noise_seed=1)
        region = metrics.penumbra_region(gt.visibility)
        noise = metrics.rmse(gt.second.visibility, gt.visibility, region) if gt.second is not None else 0.0
        for method in args.methods:
            try:
                auto = r.render(scene, method, map_size="auto", outputs=["visibility"])
                fixed = r.render(scene, method, map_size=2048, outputs=["visibility"])
            except penumbra.PenumbraError as e:
                print(f"| {name} | {method} | refused: {e} |")
                continue
            times: dict[str, list[float]] = {"auto": [], "2048": []}
            for _ in range(3):
                times["auto"].append(r.render(scene, method, map_size="auto", outputs=["visibility"]).total_ms)
                times["2048"].append(r.render(scene, method, map_size=2048, outputs=["visibility"]).total_ms)
            e_auto = metrics.rmse(auto.visibility, gt.visibility, region)
            e_fixed = metrics.rmse(fixed.visibility, gt.visibility, region)
            ratio = statistics.median(times["auto"]) / statistics.median(times["2048"])
            ratios.append(ratio)
            ok = e_auto - e_fixed <= noise
            worst = max(worst, (e_auto - e_fixed) - noise)
            print(f"| {name} | {method} | {auto.stats['map_size']} | {e_auto:.4f} | {e_fixed:.4f} | {noise:.4f} | "
                  f"{'yes' if ok else '**no**'} | {ratio:.2f} |", flush=True)
    print(f"\nworst (auto - 2048) - noise: {worst:+.4f}; time auto / 2048: median {float(np.median(ratios)):.2f}, "
          f"range {min(ratios):.2f}-{max(ratios):.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Method `raytraced` against Mitsuba ground truth on every built-in scene and
the real meshes: the penumbra visibility RMSE at each sample count, beside
the noise of both estimators (each measured from a second seed), and how
the error falls with the sample count.

For each scene: Mitsuba's visibility at `--spp` (seed 0, and seed 1 for its
noise), `raytraced` at each of `--samples` (seed 0, and seed 1 for its
noise). Columns: RMSE over the penumbra region (Mitsuba's visibility in
(0.02, 0.98)) against Mitsuba; raytraced's own noise (seed-to-seed RMSE /
sqrt 2); the combined noise sqrt(mitsuba^2 + raytraced^2); their ratio
(about 1 when nothing but noise separates the two: no bias); then the
slope of log(raytraced noise) against log(n) (-0.5: error as 1/sqrt(n)).

    python benchmarks/raytraced_accuracy.py [--size 96] [--spp 1024] [--samples 16 64 256 1024]
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

import penumbra
from penumbra import metrics
from penumbra.mitsuba import ground_truth

MESHES = Path(__file__).resolve().parents[1] / ".." / "shared" / "meshes"
REAL = ["cube.obj", "spot.obj", "teapot-mcguire-closed.obj", "bun_zipper_res4.ply", "CornellBox-Original.obj"]


def scenes(size: int) -> dict[str, penumbra.Scene]:
    out = {n: penumbra.scenes.get(n, width=size, height=size) for n in penumbra.scenes.names()}
    for name in REAL:
        if (MESHES / name).exists():
            make = penumbra.scenes.cornell_box if name.startswith("CornellBox") else penumbra.scenes.from_mesh
            out[name] = make(str(MESHES / name), width=size, height=size)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=96)
    parser.add_argument("--spp", type=int, default=1024)
    parser.add_argument("--samples", type=int, nargs="+", default=[16, 64, 256, 1024])
    args = parser.parse_args()
    renderer = penumbra.Renderer()
    print(f"adapter: {renderer.adapter_info['name']} ({renderer.adapter_info['driver_info']}); {args.size}x{args.size}; Mitsuba at {args.spp} spp\n")
    print("| scene | n_samples | penumbra RMSE vs Mitsuba | Mitsuba noise | raytraced noise | combined noise | RMSE / combined |")
    print("|---|---|---|---|---|---|---|")
    slopes = []
    for name, scene in scenes(args.size).items():
        gt = ground_truth(scene, spp=args.spp, seed=0, noise_seed=1, kinds=["visibility"])
        region = metrics.penumbra_region(gt.visibility)
        gt_noise = metrics.rmse(gt.visibility, gt.second.visibility, region) / math.sqrt(2)
        noise = []
        for n in args.samples:
            a = renderer.render(scene, "raytraced", n_samples=n, seed=0).visibility
            b = renderer.render(scene, "raytraced", n_samples=n, seed=1).visibility
            error = metrics.rmse(a, gt.visibility, region)
            own = metrics.rmse(a, b, region) / math.sqrt(2)
            combined = math.hypot(gt_noise, own)
            noise.append(own)
            print(f"| {name} | {n} | {error:.4f} | {gt_noise:.4f} | {own:.4f} | {combined:.4f} | {error / combined:.2f} |")
        slope = float(np.polyfit(np.log(args.samples), np.log(noise), 1)[0])
        slopes.append(slope)
        print(f"| {name} | slope of raytraced noise against n | {slope:.2f} | | | | |")
    print(f"\nslopes: min {min(slopes):.2f}, max {max(slopes):.2f} (-0.5 is 1/sqrt(n))")


if __name__ == "__main__":
    main()

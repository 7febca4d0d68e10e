"""Method `raytraced` measured: the numbers of docs/methods/raytraced.md
(its time against Mitsuba's and reference's: `penumbra bench --config
benchmarks/raytraced.toml`, its time_to_error.md). Scenes:
every built-in scene and the real meshes (cube, spot, teapot, the small
bunny, placed as from_mesh's default, and the Cornell box).

    python benchmarks/raytraced.py accuracy [--size 96] [--spp 1024] [--samples 16 64 256 1024]
    python benchmarks/raytraced.py adaptive [--size 128] [--n-samples 256]

`accuracy`: For each scene: Mitsuba's visibility at `--spp` (seed 0, and seed 1 for its
noise), `raytraced` at each of `--samples` (seed 0, and seed 1 for its
noise). Columns: RMSE over the penumbra region (Mitsuba's visibility in
(0.02, 0.98)) against Mitsuba; raytraced's own noise (seed-to-seed RMSE /
sqrt 2); the combined noise sqrt(mitsuba^2 + raytraced^2); their ratio
(about 1 when nothing but noise separates the two: no bias); then the
slope of log(raytraced noise) against log(n) (-0.5: error as 1/sqrt(n)).

`adaptive`: against its plain mode (the full
sample count at every pixel): how many pixels take the full count, how many
it misses, and what that costs in time, on every built-in scene and the
real meshes, for several first-pass sample counts and radii.

A pixel is missed when adaptive mode kept its first-pass estimate (0 or 1)
where plain mode sees a penumbra: |adaptive - plain| > 0.01 (refined pixels
equal plain mode's exactly, same samples). Columns: pixels that took the
full count (% of geometry pixels), misses (pixels and % of plain mode's
penumbra pixels, visibility in (0.02, 0.98)), the largest difference, the
RMSE between the two over plain mode's penumbra, and time over plain mode's
(medians of 3 renders after a warm-up, in one run).
"""

from __future__ import annotations

import argparse
import math
import statistics

import numpy as np

import penumbra
from penumbra import metrics
from penumbra.mitsuba import ground_truth

REAL = ["cube.obj", "spot.obj", "teapot-mcguire-closed.obj", "bun_zipper_res4.ply"]
SETTINGS = [(4, 1), (4, 2), (8, 1), (8, 2), (16, 1), (16, 2)]


def scenes(size: int) -> dict[str, penumbra.Scene]:
    """The built-in scenes and, with the shared meshes, the real ones."""
    out = {n: penumbra.scenes.get(n, width=size, height=size) for n in penumbra.scenes.names()}
    root = penumbra.scenes.meshes_folder()
    if root is not None:
        out.update({name: penumbra.scenes.from_mesh(str(root / name), width=size, height=size) for name in REAL})
        out["CornellBox-Original.obj"] = penumbra.scenes.get("cornell_box", width=size, height=size)
    return out


def accuracy(args: argparse.Namespace) -> None:
    renderer = penumbra.Renderer()
    print(f"adapter: {renderer.adapter_info['name']} ({renderer.adapter_info['driver_info']}); {args.size}x{args.size}; Mitsuba at {args.spp} spp\n")
    print("| scene | n_samples | penumbra RMSE vs Mitsuba | Mitsuba noise | raytraced noise | combined noise | RMSE / combined |")
    print("|---|---|---|---|---|---|---|")
    slopes = []
    for name, scene in scenes(args.size).items():
        gt = ground_truth(scene, spp=args.spp, seed=0, noise_seed=1, kinds=["visibility"])
        region = metrics.penumbra_region(gt.visibility)
        gt_noise = metrics.seed_noise(gt.visibility, gt.second.visibility, region)
        noise = []
        for n in args.samples:
            a = renderer.render(scene, "raytraced", n_samples=n, seed=0).visibility
            b = renderer.render(scene, "raytraced", n_samples=n, seed=1).visibility
            error = metrics.rmse(a, gt.visibility, region)
            own = metrics.seed_noise(a, b, region)
            combined = math.hypot(gt_noise, own)
            noise.append(own)
            print(f"| {name} | {n} | {error:.4f} | {gt_noise:.4f} | {own:.4f} | {combined:.4f} | {error / combined:.2f} |")
        slope = float(np.polyfit(np.log(args.samples), np.log(noise), 1)[0])
        slopes.append(slope)
        print(f"| {name} | slope of raytraced noise against n | {slope:.2f} | | | | |")
    print(f"\nslopes: min {min(slopes):.2f}, max {max(slopes):.2f} (-0.5 is 1/sqrt(n))")


def timed(renderer: penumbra.Renderer, scene: penumbra.Scene, **params: object) -> tuple[penumbra.RenderResult, float]:
    renderer.render(scene, "raytraced", **params)
    runs = [renderer.render(scene, "raytraced", **params) for _ in range(3)]
    return runs[-1], statistics.median(r.total_ms for r in runs)



def adaptive(args: argparse.Namespace) -> None:
    renderer = penumbra.Renderer(timing="cpu", pass_cache=False)
    print(f"adapter: {renderer.adapter_info['name']} ({renderer.adapter_info['driver_info']}); {args.size}x{args.size}; n_samples {args.n_samples}\n")
    print("| scene | adaptive_samples | adaptive_radius | full pixels | missed pixels | missed / penumbra | max difference | RMSE vs plain (penumbra) | time / plain |")
    print("|---|---|---|---|---|---|---|---|---|")
    totals: dict[tuple[int, int], list[int]] = {s: [0, 0] for s in SETTINGS}
    for name, scene in scenes(args.size).items():
        plain, plain_ms = timed(renderer, scene, n_samples=args.n_samples)
        geometry = int(plain.stats["geometry_pixels"])
        region = metrics.penumbra_region(plain.visibility)
        for k, r in SETTINGS:
            result, ms = timed(renderer, scene, n_samples=args.n_samples, adaptive=True, adaptive_samples=k, adaptive_radius=r)
            d = np.abs(result.visibility.astype(np.float64) - plain.visibility)
            missed = int((d > 0.01).sum())
            totals[(k, r)][0] += missed
            totals[(k, r)][1] += int(region.sum())
            print(
                f"| {name} | {k} | {r} | {100 * result.stats['full_pixels'] / geometry:.1f}% | {missed} | "
                f"{100 * missed / max(int(region.sum()), 1):.2f}% | {d.max():.3f} | {metrics.rmse(result.visibility, plain.visibility, region):.4f} | {ms / plain_ms:.2f} |"
            )
    print("\nAll scenes: missed pixels / plain mode's penumbra pixels")
    for (k, r), (missed, penumbra_pixels) in totals.items():
        print(f"- adaptive_samples={k}, adaptive_radius={r}: {missed} / {penumbra_pixels} ({100 * missed / max(penumbra_pixels, 1):.2f}%)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="what", required=True)
    a = sub.add_parser("accuracy")
    a.add_argument("--size", type=int, default=96)
    a.add_argument("--spp", type=int, default=1024)
    a.add_argument("--samples", type=int, nargs="+", default=[16, 64, 256, 1024])
    b = sub.add_parser("adaptive")
    b.add_argument("--size", type=int, default=128)
    b.add_argument("--n-samples", type=int, default=256)
    args = parser.parse_args()
    accuracy(args) if args.what == "accuracy" else adaptive(args)


if __name__ == "__main__":
    main()

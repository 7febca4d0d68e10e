"""Adaptive mode of method `raytraced` against its plain mode (the full
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

    python benchmarks/raytraced_adaptive.py [--size 128] [--n-samples 256]
"""

from __future__ import annotations

import argparse
import statistics
from pathlib import Path

import numpy as np

import penumbra
from penumbra import metrics

MESHES = Path(__file__).resolve().parents[1] / ".." / "shared" / "meshes"
REAL = ["cube.obj", "spot.obj", "teapot-mcguire-closed.obj", "bun_zipper_res4.ply", "CornellBox-Original.obj"]
SETTINGS = [(4, 1), (4, 2), (8, 1), (8, 2), (16, 1), (16, 2)]


def scenes(size: int) -> dict[str, penumbra.Scene]:
    out = {n: penumbra.scenes.get(n, width=size, height=size) for n in penumbra.scenes.names()}
    for name in REAL:
        if (MESHES / name).exists():
            make = penumbra.scenes.cornell_box if name.startswith("CornellBox") else penumbra.scenes.from_mesh
            out[name] = make(str(MESHES / name), width=size, height=size)
    return out


def timed(renderer: penumbra.Renderer, scene: penumbra.Scene, **params: object) -> tuple[penumbra.RenderResult, float]:
    renderer.render(scene, "raytraced", **params)
    runs = [renderer.render(scene, "raytraced", **params) for _ in range(3)]
    return runs[-1], statistics.median(r.total_ms for r in runs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=128)
    parser.add_argument("--n-samples", type=int, default=256)
    args = parser.parse_args()
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


if __name__ == "__main__":
    main()

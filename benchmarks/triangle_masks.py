"""Method `triangle_masks` (issue 34): its agreement with `raytraced` and
`reference`, and its time against theirs at the same light samples
(docs/methods/triangle_masks.md has the tables).

    python3 benchmarks/triangle_masks.py agreement [--size 64]
    python3 benchmarks/triangle_masks.py time [--size 256] [--samples 64 256 1024] [--budget 120]

`time` renders the default scene and the full Stanford bunny
(../shared/meshes/bun_zipper.ply, 69k triangles) with each method, warm (one
render first, pass cache off), CPU clocks; a method whose render at a
sample count took longer than `--budget` seconds is not run at the larger
counts (its row says so). It also prints the cost per triangle-pixel pair
(the `masks` pass over `triangle_pixel_pairs`).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import penumbra

MESHES = Path(__file__).resolve().parents[1] / ".." / "shared" / "meshes"
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))


def agreement(size: int) -> None:
    from test_triangle_masks import scenes

    renderer = penumbra.Renderer()
    rays = bool(renderer.adapter_info.get("ray_queries"))
    print("| scene | n | px | vs raytraced: max | px > 1e-5 | vs reference: mean | px > 1/n |")
    print("|---|---|---|---|---|---|---|")
    for n in (64, 256):
        for name, scene in scenes(size).items():
            masks = renderer.render(scene, "triangle_masks", n_samples=n)
            geometry = masks.object_id >= 0
            reference = np.abs(masks.visibility - renderer.render(scene, "reference", n_samples=n).visibility)[geometry]
            rt = "no ray queries", ""
            if rays:
                d = np.abs(masks.visibility - renderer.render(scene, "raytraced", n_samples=n).visibility)[geometry]
                rt = f"{d.max():.2e}", str(int((d > 1e-5).sum()))
            print(f"| {name} | {n} | {geometry.sum()} | {rt[0]} | {rt[1]} | {reference.mean():.4f} | {int((reference > 1 / n + 1e-6).sum())} |")


def timing(size: int, samples: list[int], budget: float) -> None:
    renderer = penumbra.Renderer(timing="cpu", pass_cache=False)
    cases = {"sphere_on_plane": penumbra.scenes.get(width=size, height=size)}
    if (MESHES / "bun_zipper.ply").exists():
        cases["bun_zipper.ply"] = penumbra.scenes.from_mesh(str(MESHES / "bun_zipper.ply"), width=size, height=size)
    methods = ["triangle_masks", "reference"] + (["raytraced"] if renderer.adapter_info.get("ray_queries") else [])
    print(f"{size}x{size}, {renderer.adapter_info['name']}; seconds per warm render")
    print("| scene | n_samples | " + " | ".join(methods) + " | triangle_masks: pairs | ns per pair (masks pass) |")
    print("|---|---|" + "---|" * len(methods) + "---|---|")
    for name, scene in cases.items():
        over: set[str] = set()
        for n in samples:
            row, pairs, per_pair = [], "", ""
            for method in methods:
                if method in over:
                    row.append(f"> {budget:.0f} s at fewer")
                    continue
                renderer.render(scene, method, n_samples=n)
                start = time.perf_counter()
                result = renderer.render(scene, method, n_samples=n)
                seconds = time.perf_counter() - start
                row.append(f"{seconds:.2f}")
                if seconds > budget:
                    over.add(method)
                if method == "triangle_masks":
                    p = result.stats["triangle_pixel_pairs"]
                    pairs = f"{p} ({result.stats['pairs_tested_per_sample']} per sample)"
                    per_pair = f"{1e6 * result.timings['masks'] / max(p, 1):.0f}"
            print(f"| {name} | {n} | " + " | ".join(row) + f" | {pairs} | {per_pair} |", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="what", required=True)
    a = sub.add_parser("agreement")
    a.add_argument("--size", type=int, default=64)
    t = sub.add_parser("time")
    t.add_argument("--size", type=int, default=256)
    t.add_argument("--samples", type=int, nargs="+", default=[64, 256, 1024])
    t.add_argument("--budget", type=float, default=120.0)
    args = parser.parse_args()
    if args.what == "agreement":
        agreement(args.size)
    else:
        timing(args.size, args.samples, args.budget)


if __name__ == "__main__":
    main()

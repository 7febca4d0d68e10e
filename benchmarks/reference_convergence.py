"""Convergence of `reference` to Mitsuba ground truth as n_samples grows.

For every built-in scene: the penumbra visibility RMSE of `reference` at
16, 64, 256 and 1024 light samples against ground truth, beside the ground
truth's own noise (second seed); and, on the default scene, 1024 samples at
other map sizes, to separate the shadow-map resolution error.

    python benchmarks/reference_convergence.py [--size 128] [--spp 4096]
"""

from __future__ import annotations

import argparse

import penumbra
from penumbra import metrics
from penumbra import mitsuba as pm


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=128)
    parser.add_argument("--spp", type=int, default=4096)
    parser.add_argument("--samples", type=int, nargs="+", default=[16, 64, 256, 1024])
    args = parser.parse_args()
    renderer = penumbra.Renderer(timing="cpu")
    print(f"{args.size}x{args.size}; ground truth Mitsuba {pm.variant()} at {args.spp} spp; map_size 2048 unless stated\n")
    print("| scene | " + " | ".join(f"n = {n}" for n in args.samples) + " | ground-truth noise |")
    print("|---|" + "---|" * (len(args.samples) + 1))
    for name in penumbra.scenes.names():
        scene = penumbra.scenes.get(name, width=args.size, height=args.size)
        gt = pm.ground_truth(scene, spp=args.spp, noise_seed=1, kinds=["visibility"])
        cells = []
        for n in args.samples:
            m = metrics.compare(renderer.render(scene, "reference", n_samples=n), gt)
            cells.append(f"{m['visibility_rmse_penumbra']:.4f}")
        print(f"| {name} | " + " | ".join(cells) + f" | {m['noise_visibility_rmse_penumbra']:.4f} |")
    scene = penumbra.scenes.get(width=args.size, height=args.size)
    gt = pm.ground_truth(scene, spp=args.spp, noise_seed=1, kinds=["visibility"])
    print("\n| default scene, n = 1024 | map_size 512 | map_size 1024 | map_size 2048 | map_size 4096 |")
    print("|---|---|---|---|---|")
    cells = []
    for size in (512, 1024, 2048, 4096):
        m = metrics.compare(renderer.render(scene, "reference", n_samples=1024, map_size=size), gt)
        cells.append(f"{m['visibility_rmse_penumbra']:.4f}")
    print("| penumbra RMSE | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()

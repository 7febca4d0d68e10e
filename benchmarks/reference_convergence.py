"""Convergence of `reference` to Mitsuba ground truth as n_samples grows.

For every built-in scene: the penumbra visibility RMSE of `reference`
(default `sampling="sphere"`, and Herf's facing `disk`) at 16, 64, 256 and
1024 light samples against ground truth. At 1024 samples the error is taken
apart: the ground truth's own noise (its second seed), the sampling noise
(the same render with another seed, the RMSE between them over sqrt(2)) and
the shadow-map resolution error (the same samples with a 4096 map instead of
2048: what the finite map adds), beside the convergence criterion of issue 6,
twice the ground-truth noise plus the resolution error.

    python benchmarks/reference_convergence.py [--size 128] [--spp 4096] [--sampling sphere disk] [--scenes ...]
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
    parser.add_argument("--sampling", nargs="+", default=["sphere", "disk"], choices=["sphere", "disk"])
    parser.add_argument("--scenes", nargs="+", default=penumbra.scenes.names())
    parser.add_argument("--beyond", type=int, help="also one sphere render at this many samples, against the criterion of the largest --samples")
    args = parser.parse_args()
    args.samples = sorted(args.samples)
    renderer = penumbra.Renderer(timing="cpu", pass_cache=False)
    n_max = max(args.samples)
    print(f"{args.size}x{args.size}; ground truth Mitsuba {pm.variant()} at {args.spp} spp; map_size 2048 unless stated\n")
    head = "| scene | sampling | " + " | ".join(f"n = {n}" for n in args.samples) + " |"
    convergence = [head, "|---|---|" + "---|" * len(args.samples)]
    parts = [
        f"| scene | sampling | error at n = {n_max} | ground-truth noise | sampling noise | resolution error | "
        "criterion: 2 x noise + resolution | met |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name in args.scenes:
        scene = penumbra.scenes.get(name, width=args.size, height=args.size)
        gt = pm.ground_truth(scene, spp=args.spp, noise_seed=1, kinds=["visibility"])
        region = metrics.penumbra_region(gt.visibility)
        for sampling in args.sampling:
            cells = []
            for n in args.samples:
                result = renderer.render(scene, "reference", n_samples=n, sampling=sampling)
                m = metrics.compare(result, gt)
                cells.append(f"{m['visibility_rmse_penumbra']:.4f}")
            convergence.append(f"| {name} | {sampling} | " + " | ".join(cells) + " |")
            print(convergence[-1], flush=True)
            if sampling != "sphere":
                continue
            base = result.visibility  # n_max, the last of the sorted sample counts
            other_seed = renderer.render(scene, "reference", n_samples=n_max, seed=1).visibility
            finer = renderer.render(scene, "reference", n_samples=n_max, map_size=4096).visibility
            error = metrics.rmse(base, gt.visibility, region)
            noise = m["noise_visibility_rmse_penumbra"]
            sampling_noise = metrics.seed_noise(base, other_seed, region)
            resolution = metrics.rmse(base, finer, region)
            bound = 2 * noise + resolution
            parts.append(
                f"| {name} | {sampling} | {error:.4f} | {noise:.4f} | {sampling_noise:.4f} | {resolution:.4f} | {bound:.4f} | "
                f"{'yes' if error <= bound else 'no'} |"
            )
            print(parts[-1], flush=True)
            if args.beyond:
                far = metrics.rmse(renderer.render(scene, "reference", n_samples=args.beyond).visibility, gt.visibility, region)
                parts.append(f"| {name} | {sampling}, n = {args.beyond} | {far:.4f} | | | | {bound:.4f} (n = {n_max}) | {'yes' if far <= bound else 'no'} |")
                print(parts[-1], flush=True)
    print()
    print("\n".join(convergence))
    print()
    print("\n".join(parts))


if __name__ == "__main__":
    main()

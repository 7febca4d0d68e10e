"""The error of `reference` at many light samples taken apart, against the
convergence criterion of issue 6 (docs/methods/reference.md; its convergence
as n_samples grows: `penumbra bench --config benchmarks/reference.toml`).

For each scene: the penumbra visibility RMSE of `reference` (sphere sampling)
at `--samples` against Mitsuba ground truth, the ground truth's own noise (its
second seed), the sampling noise (the same render with another seed, the RMSE
between them over sqrt(2)) and the shadow-map resolution error (the same
samples with a 4096 map instead of 2048: what the finite map adds), beside
the criterion, twice the ground-truth noise plus the resolution error, and
how many of the light samples' maps were cube maps (the wide floor's).

    python benchmarks/reference_convergence.py [--size 128] [--spp 4096] [--samples 1024] [--scenes ...] [--beyond N]
    python benchmarks/reference_convergence.py --scenes wide_floor:spot.obj --spp 1024   # docs/omnidirectional.md
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
    parser.add_argument("--samples", type=int, default=1024)
    parser.add_argument("--scenes", nargs="+", default=penumbra.scenes.names(), help="scene names (penumbra.scenes.get)")
    parser.add_argument("--beyond", type=int, help="also the error at this many samples, against the criterion at --samples")
    args = parser.parse_args()
    renderer = penumbra.Renderer(timing="cpu", pass_cache=False)
    n = args.samples
    print(f"{args.size}x{args.size}; ground truth Mitsuba {pm.variant()} at {args.spp} spp; map_size 2048 unless stated\n")
    print(f"| scene | sampling | error at n = {n} | ground-truth noise | sampling noise | resolution error | "
          "criterion: 2 x noise + resolution | met | cube maps |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name in args.scenes:
        scene = penumbra.scenes.get(name, width=args.size, height=args.size)
        gt = pm.ground_truth(scene, spp=args.spp, noise_seed=1, kinds=["visibility"])
        assert gt.second is not None
        region = metrics.penumbra_region(gt.visibility)
        result = renderer.render(scene, "reference", n_samples=n)
        other_seed = renderer.render(scene, "reference", n_samples=n, seed=1).visibility
        finer = renderer.render(scene, "reference", n_samples=n, map_size=4096).visibility
        error = metrics.rmse(result.visibility, gt.visibility, region)
        noise = metrics.seed_noise(gt.visibility, gt.second.visibility, region)
        sampling_noise = metrics.seed_noise(result.visibility, other_seed, region)
        resolution = metrics.rmse(result.visibility, finer, region)
        bound = 2 * noise + resolution
        print(f"| {name} | sphere | {error:.4f} | {noise:.4f} | {sampling_noise:.4f} | {resolution:.4f} | {bound:.4f} | "
              f"{'yes' if error <= bound else 'no'} | {result.stats['cube_maps']} of {result.stats['light_samples']} |", flush=True)
        if args.beyond:
            far = metrics.rmse(renderer.render(scene, "reference", n_samples=args.beyond).visibility, gt.visibility, region)
            print(f"| {name} | sphere, n = {args.beyond} | {far:.4f} | | | | {bound:.4f} (n = {n}) | {'yes' if far <= bound else 'no'} | |", flush=True)


if __name__ == "__main__":
    main()

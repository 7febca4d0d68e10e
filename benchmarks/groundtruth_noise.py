"""Ground-truth cost and noise floor against samples per pixel.

Renders Mitsuba ground truth of a built-in scene with two seeds at each spp
(no cache) and prints a markdown table: seconds per render (radiance,
visibility) and each image's noise (the seed-to-seed RMSE divided by sqrt(2)):
visibility over all pixels and over the penumbra, radiance relative to the lit mean.

    python benchmarks/groundtruth_noise.py [--scene sphere_on_plane] [--size 256] [--spp 16 64 256 1024 4096]
"""

from __future__ import annotations

import argparse

import penumbra
from penumbra import metrics
from penumbra import mitsuba as pm


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scene", default=penumbra.scenes.DEFAULT)
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--spp", type=int, nargs="+", default=[16, 64, 256, 1024, 4096])
    args = parser.parse_args()
    scene = penumbra.scenes.get(args.scene, width=args.size, height=args.size)
    print(f"scene {args.scene}, {args.size}x{args.size}, Mitsuba {pm.variant()}\n")
    print("| spp | radiance s | visibility s | visibility noise (all) | visibility noise (penumbra) | radiance noise (rel. to lit mean) |")
    print("|---|---|---|---|---|---|")
    for spp in args.spp:
        a = pm.ground_truth(scene, spp=spp, seed=0, cache=False)
        b = pm.ground_truth(scene, spp=spp, seed=1, cache=False)
        region = metrics.penumbra_region(a.visibility)
        noise_all = metrics.seed_noise(a.visibility, b.visibility)
        noise_pen = metrics.seed_noise(a.visibility, b.visibility, region)
        noise_rad = metrics.seed_noise(a.radiance, b.radiance) / metrics.lit_mean(a.radiance, a.visibility)
        rspp = pm.radiance_spp(spp)
        label = f"{spp}" if rspp == spp else f"{spp} (radiance {rspp})"
        print(f"| {label} | {a.seconds['radiance']:.2f} | {a.seconds['visibility']:.2f} | {noise_all:.5f} | {noise_pen:.5f} | {noise_rad:.5f} |")


if __name__ == "__main__":
    main()

"""`wedges` on the generated scenes (issue 28): the before/after table of
docs/methods/wedges.md, from one command.

For seeds `--first` to `--first + --count - 1` of `penumbra.scenes.generate`
at `--size`, against Mitsuba visibility at `--spp` (cached as `penumbra
compare` does): per variant, the median and worst penumbra RMSE, how many
scenes are at most 0.5x `hard`'s RMSE and how many worse than `hard`, and
the worst stray-pixel share (`metrics.stray_pixels`). `--per-scene` adds
one row per scene.

    python benchmarks/wedges_generated.py [--first 0] [--count 40] [--size 96] [--spp 256] [--per-scene]
"""

from __future__ import annotations

import argparse
import statistics
from typing import Any

import numpy as np

import penumbra
from penumbra import metrics, scenes
from penumbra.mitsuba import ground_truth

# (label, method, parameters)
VARIANTS: list[tuple[str, str, dict[str, Any]]] = [
    ("hard", "hard", {}),
    ("pcss", "pcss", {}),
    ("wedges, 2002 interpolation (old default)", "wedges", {"intensity": "interpolation", "overlap": "sum"}),
    ("wedges, coverage, overlap=sum", "wedges", {"intensity": "coverage", "overlap": "sum"}),
    ("wedges, interpolation, overlap=gate", "wedges", {"intensity": "interpolation", "overlap": "gate"}),
    ("wedges, coverage, hidden edges kept", "wedges", {"intensity": "coverage", "overlap": "sum", "repairs": "cone+horizon"}),
    ("wedges (defaults: coverage, overlap=gate)", "wedges", {}),
]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--count", type=int, default=40)
    ap.add_argument("--size", type=int, default=96)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--per-scene", action="store_true")
    args = ap.parse_args()
    renderer = penumbra.Renderer()
    rmse: dict[str, list[float]] = {label: [] for label, _, _ in VARIANTS}
    stray: dict[str, list[float]] = {label: [] for label, _, _ in VARIANTS}
    rows = []
    for seed in range(args.first, args.first + args.count):
        scene = scenes.generate(seed, width=args.size)
        truth = ground_truth(scene, spp=args.spp)
        row = [scene.name]
        for label, method, params in VARIANTS:
            out = renderer.render(scene, method, **params)
            e = metrics.compare_images(out.visibility, truth)["visibility_rmse_penumbra"]
            bad, of = metrics.stray_pixels(out.visibility, truth.images["visibility"])
            rmse[label].append(e)
            stray[label].append(100.0 * bad / max(of, 1))
            row.append(f"{e:.3f} ({100.0 * bad / max(of, 1):.2f})")
        rows.append(row)
        print(" | ".join(row), flush=True)
    hard = np.array(rmse["hard"])
    print()
    print(f"{args.count} generated scenes (seeds {args.first}-{args.first + args.count - 1}), {args.size}x{args.size}, Mitsuba at {args.spp} spp")
    print()
    print("| variant | median penumbra RMSE | worst | at most 0.5x hard's | worse than hard | worst stray % | scenes over 0.5% stray |")
    print("|---|---|---|---|---|---|---|")
    for label, _, _ in VARIANTS:
        errors = np.array(rmse[label])
        strays = np.array(stray[label])
        print(
            f"| {label} | {statistics.median(errors):.3f} | {errors.max():.3f} | {(errors <= 0.5 * hard).sum()} of {len(errors)} | "
            f"{(errors > hard).sum()} | {strays.max():.2f} | {(strays > 0.5).sum()} |"
        )
    if args.per_scene:
        print()
        print("| scene | " + " | ".join(label for label, _, _ in VARIANTS) + " |")
        print("|---|" + "---|" * len(VARIANTS))
        for row in rows:
            print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()

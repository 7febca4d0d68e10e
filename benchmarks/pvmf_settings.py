"""PVMF's settings against ground truth: the paper's defaults and each
option beyond the paper, one at a time, on every built-in scene.

Prints a markdown table of penumbra visibility RMSE (pixels whose ground-truth
visibility is strictly between 0.02 and 0.98) with `pvm`, `hard` and the
ground truth's own noise for scale.

    python benchmarks/pvmf_settings.py [--size 256] [--spp 1024]
"""

from __future__ import annotations

import argparse
from typing import Any

import penumbra
from penumbra import metrics
from penumbra import mitsuba as pm

SETTINGS: list[tuple[str, dict[str, Any]]] = [
    ("pvmf", {}),
    ("pvmf", {"n_blur": 0}),
    ("pvmf", {"n_blur": 4}),
    ("pvmf", {"kernel": "disk"}),
    ("pvmf", {"kernel": "disk", "n_blur": 0}),
    ("pvmf", {"s_p": 1.5}),
    ("pvmf", {"s_p": 2.5}),
    ("pvmf", {"bias": "midpoint"}),
    ("pvmf", {"bias": "slope"}),
    ("pvmf", {"filter": "nearest"}),
    ("pvmf", {"offsets": "radius"}),
    ("pvmf", {"umbra": "skip"}),
    ("pvmf", {"kernel": "disk", "n_blur": 0, "offsets": "radius", "umbra": "skip"}),
    ("pvm", {"falloff": False}),
    ("hard", {}),
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--spp", type=int, default=1024)
    args = parser.parse_args()
    renderer = penumbra.Renderer()
    names = penumbra.scenes.names()
    scenes = {n: penumbra.scenes.get(n, width=args.size, height=args.size) for n in names}
    truth = {n: pm.ground_truth(s, spp=args.spp, noise_seed=1) for n, s in scenes.items()}
    print(f"{args.size}x{args.size}; ground truth Mitsuba {pm.variant()} at {args.spp} spp; penumbra visibility RMSE; filtered = mean filtered pixels\n")
    print("| method | settings | " + " | ".join(names) + " | filtered |")
    print("|---|---|" + "---|" * len(names) + "---|")
    noise = []
    for method, params in SETTINGS:
        errors, filtered = [], []
        for n in names:
            result = renderer.render(scenes[n], method, **params)
            m = metrics.compare(result, truth[n])
            errors.append(f"{m['visibility_rmse_penumbra']:.4f}")
            filtered.append(result.stats.get("filtered_pixels", 0))
            if not noise or len(noise) < len(names):
                noise.append(f"{m['noise_visibility_rmse_penumbra']:.4f}")
        shown = ", ".join(f"{k}={v}" for k, v in params.items()) or "paper (defaults)"
        mean_filtered = f"{sum(filtered) / len(filtered):.0f}" if method == "pvmf" else ""
        print(f"| {method} | {shown} | " + " | ".join(errors) + f" | {mean_filtered} |")
    print("| *ground-truth noise* | | " + " | ".join(noise) + " | |")


if __name__ == "__main__":
    main()

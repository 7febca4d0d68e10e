"""Method `triangle_masks` (issue 34): its agreement with `raytraced` and
`reference` at the same light samples, on tests/test_triangle_masks.py's
scenes (docs/methods/triangle_masks.md; its cost against theirs:
`penumbra bench --config benchmarks/triangle_masks.toml`).

    python3 benchmarks/triangle_masks.py agreement [--size 64]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import penumbra

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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("what", choices=["agreement"])
    parser.add_argument("--size", type=int, default=64)
    agreement(parser.parse_args().size)


if __name__ == "__main__":
    main()

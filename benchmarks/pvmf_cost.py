"""PVMF's cost follows the penumbra (issue 5): one scene, the light's radius
swept, so the penumbra's area on screen grows while the image stays the same.

For each radius, prints the penumbra's area (pixels with 0.02 < v < 0.98 in
`reference` with 256 samples), PVMF's masked, filtered and blurred pixel
counts, and the median CPU time of its estimation and blur passes over
repeated renders (after a warm-up, in this one process), with `hard`'s
visibility pass as the unit: the pass PVMF's estimation replaces.

    python benchmarks/pvmf_cost.py [--scene cube_on_plane] [--size 256] [--repeats 7]
"""

from __future__ import annotations

import argparse
import statistics
from typing import Any

import penumbra

RADII = [0.0, 0.1, 0.25, 0.5, 1.0, 1.5]
SETTINGS: list[tuple[str, dict[str, Any]]] = [
    ("paper", {}),
    ("radius offsets, umbra skipped", {"offsets": "radius", "umbra": "skip"}),
]


def median_pass_ms(renderer: penumbra.Renderer, scene: penumbra.Scene, method: str, params: dict[str, Any], passes: list[str], repeats: int) -> tuple[dict[str, float], penumbra.RenderResult]:
    result = renderer.render(scene, method, **params)
    samples: dict[str, list[float]] = {p: [] for p in passes}
    for _ in range(repeats):
        result = renderer.render(scene, method, **params)
        for p in passes:
            samples[p].append(result.timings.get(p, 0.0))
    return {p: statistics.median(v) for p, v in samples.items()}, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scene", default="cube_on_plane")
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    # CPU clocks around each pass (submitted and waited for alone): lavapipe's
    # timestamps are not trusted (see the README's "Timings"). No pass
    # cache: every repeat runs every pass.
    renderer = penumbra.Renderer(timing="cpu", pass_cache=False)
    print(f"adapter {renderer.adapter_info['name']}; scene {args.scene} at {args.size}x{args.size}; median of {args.repeats} renders\n")
    print("| settings | radius | penumbra pixels | masked | filtered | blurred | estimation / hard visibility | blur / hard visibility |")
    print("|---|---|---|---|---|---|---|---|")
    for label, params in SETTINGS:
        for radius in RADII:
            scene = penumbra.scenes.get(args.scene, width=args.size, height=args.size, light_radius=radius)
            reference = renderer.render(scene, "reference", n_samples=256)
            v = reference.visibility
            area = int(((v > 0.02) & (v < 0.98) & (reference.object_id >= 0)).sum())
            hard, _ = median_pass_ms(renderer, scene, "hard", {}, ["visibility"], args.repeats)
            pvmf, result = median_pass_ms(renderer, scene, "pvmf", params, ["estimation", "blur"], args.repeats)
            s = result.stats
            unit = hard["visibility"]
            print(
                f"| {label} | {radius} | {area} | {s['masked_pixels']} | {s['filtered_pixels']} | {s['blurred_pixels']} | "
                f"{pvmf['estimation'] / unit:.2f} | {pvmf['blur'] / unit:.2f} |"
            )


if __name__ == "__main__":
    main()

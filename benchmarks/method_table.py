"""Every implemented method against Mitsuba ground truth on every built-in scene.

Prints a markdown table of the SPEC metrics (with the ground truth's own
noise), and each method's render time as a ratio to `hard` on the same scene,
measured in this one run (median of repeated renders after a warm-up; CPU
clocks around each whole render call).

    python benchmarks/method_table.py [--size 256] [--spp 1024] [--repeats 5]
"""

from __future__ import annotations

import argparse
import statistics
from typing import Any

import penumbra
from penumbra import metrics
from penumbra import mitsuba as pm
from penumbra.scenes import ground_plane

CONFIGS: list[tuple[str, dict[str, Any]]] = [
    ("hard", {}),
    ("pcf", {}),
    ("pcss", {}),
    ("pcss", {"sampling": "poisson"}),
    ("pvm", {}),
    ("pvm", {"falloff": False}),
    ("pvmf", {}),
    ("pvmf", {"kernel": "disk", "n_blur": 0, "offsets": "radius", "umbra": "skip"}),
    ("reference", {"n_samples": 256}),
]


def median_ms(renderer: penumbra.Renderer, scene: penumbra.Scene, method: str, params: dict[str, Any], repeats: int) -> tuple[float, penumbra.RenderResult]:
    result = renderer.render(scene, method, **params)
    times = []
    for _ in range(repeats):
        result = renderer.render(scene, method, **params)
        times.append(result.total_ms)
    return statistics.median(times), result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--spp", type=int, default=1024)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    # No pass cache: the repeats are timed, so every pass must run each time.
    renderer = penumbra.Renderer(pass_cache=False)
    print(f"adapter {renderer.adapter_info['name']}; {args.size}x{args.size}; ground truth Mitsuba {pm.variant()} at {args.spp} spp, noise from a second seed\n")
    print("| scene | method | params | vis. RMSE | vis. RMSE penumbra | max error | FLIP | radiance RMSE (rel.) | time / hard |")
    print("|---|---|---|---|---|---|---|---|---|")
    rows = [(name, penumbra.scenes.get(name, width=args.size, height=args.size), CONFIGS) for name in penumbra.scenes.names()]
    # open_edges measured: the default scene with an open, single-sided ground plane.
    default = penumbra.scenes.get(width=args.size, height=args.size)
    open_scene = penumbra.Scene([ground_plane(), *default.meshes[1:]], default.light, default.camera, name="sphere_on_open_plane")
    rows.append(("sphere_on_open_plane", open_scene, [("hard", {}), ("pvm", {"open_edges": "silhouette"})]))
    for name, scene, configs in rows:
        gt = pm.ground_truth(scene, spp=args.spp, noise_seed=1)
        hard_ms = None
        for method, params in configs:
            ms, result = median_ms(renderer, scene, method, params, args.repeats)
            if method == "hard" and not params:
                hard_ms = ms
            m = metrics.compare(result, gt)
            shown = ", ".join(f"{k}={v}" for k, v in params.items()) or "defaults"
            ratio = f"{ms / hard_ms:.2f}" if hard_ms else "n/a"
            print(
                f"| {name} | {method} | {shown} | {m['visibility_rmse']:.4f} | {m['visibility_rmse_penumbra']:.4f} | "
                f"{m['visibility_max_error']:.3f} | {m['visibility_flip']:.4f} | {m['radiance_rmse_rel']:.4f} | {ratio} |"
            )
        print(
            f"| {name} | *ground-truth noise* | | {m['noise_visibility_rmse']:.4f} | {m['noise_visibility_rmse_penumbra']:.4f} | "
            f"{m['noise_visibility_max_error']:.3f} | {m['noise_visibility_flip']:.4f} | {m['noise_radiance_rmse_rel']:.4f} | |"
        )


if __name__ == "__main__":
    main()

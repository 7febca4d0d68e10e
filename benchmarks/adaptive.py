"""Method `adaptive` (Schwarzler et al.) against Mitsuba and against
`reference` and `pcss`, on every built-in scene and on real meshes of
../shared/meshes: the tables of docs/methods/adaptive.md.

Rows per scene: `adaptive` at a few settings, `reference` with the paper's
ground truth of 289 samples (the regular 17 x 17 grid on the facing disk,
`sampling="disk", jitter=False`: exactly `adaptive`'s full grid at
max_depth 4), `reference` with 1024 samples (its default sampling on the
sphere), `pcss`, and `hard` for scale. Every shadow-map method but pcss at map_size 512 (the
paper's).

Columns: maps (shadow maps rendered); penumbra RMSE of visibility against
Mitsuba (pixels whose true visibility is in (0.02, 0.98)); ms, the median
wall clock of the render call over `--repeats` renders after a warm-up,
every pass recomputed (`Renderer(pass_cache=False)`); penumbra %, the true
penumbra's share of the image. Then issue 18's target per scene: adaptive
(defaults) within 10% of reference-289's error in at most 1/3 of its time.

Last, a sweep of the light's radius on sphere_on_plane: the maps adaptive
uses against the penumbra's pixel count (Figure 1 of the paper).

    python benchmarks/adaptive.py [--size 96] [--spp 1024] [--repeats 2] [--meshes ../shared/meshes] [--scenes NAME ...]
"""

from __future__ import annotations

import argparse
import statistics
from pathlib import Path
from typing import Any

import numpy as np

import penumbra
from penumbra import metrics
from penumbra import mitsuba as pm

MESHES = Path(__file__).resolve().parents[1] / ".." / "shared" / "meshes"
REAL = ("spot.obj close r=0.3", "spot.obj close r=0.8", "spot.obj wide_floor r=0.3", "teapot-mcguire-closed.obj close r=0.3")

CONFIGS: list[tuple[str, str, dict[str, Any]]] = [
    ("hard", "hard", {"map_size": 512}),
    ("adaptive", "adaptive (defaults: max_depth 4, tolerance 0)", {}),
    ("adaptive", "adaptive tolerance 16", {"tolerance": 16}),
    ("adaptive", "adaptive max_depth 3", {"max_depth": 3}),
    ("adaptive", "adaptive comparison_scale 0.5", {"comparison_scale": 0.5}),
    ("adaptive", "adaptive weights area", {"weights": "area"}),
    ("adaptive", "adaptive pcf_2x2", {"pcf_2x2": True}),
    ("reference", "reference 289 (17 x 17 regular, disk)", {"n_samples": 289, "sampling": "disk", "jitter": False, "map_size": 512}),
    ("reference", "reference 1024 (sphere)", {"n_samples": 1024, "map_size": 512}),
    ("pcss", "pcss", {}),
]


def measure(renderer: penumbra.Renderer, scene: penumbra.Scene, method: str, params: dict[str, Any], truth: np.ndarray, repeats: int) -> dict[str, float]:
    result = renderer.render(scene, method, **params)
    times = []
    for _ in range(repeats):
        result = renderer.render(scene, method, **params)
        times.append(result.total_ms)
    region = metrics.penumbra_region(truth)
    return {
        "maps": float(result.stats.get("shadow_maps_rendered", 1)),
        "rmse": metrics.rmse(result.visibility, truth, region),
        "ms": statistics.median(times),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=96)
    parser.add_argument("--spp", type=int, default=1024)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--meshes", type=Path, default=MESHES)
    parser.add_argument("--scenes", nargs="*", help="only these scenes (built-in names or real-mesh suite names)")
    args = parser.parse_args()
    renderer = penumbra.Renderer(pass_cache=False)
    scenes = {name: penumbra.scenes.get(name, width=args.size, height=args.size) for name in penumbra.scenes.names()}
    if args.meshes.is_dir():
        suite = penumbra.scenes.real_mesh_suite(str(args.meshes), width=args.size, height=args.size)
        scenes.update({name: suite[name] for name in REAL if name in suite})
    else:
        print(f"(no real meshes: {args.meshes} is absent)")
    if args.scenes:
        scenes = {name: scene for name, scene in scenes.items() if name in args.scenes}
    targets = []
    print("| scene | method | maps | penumbra RMSE | ms |")
    print("|---|---|---:|---:|---:|")
    for name, scene in scenes.items():
        truth = pm.ground_truth(scene, spp=args.spp, noise_seed=1, kinds=("visibility",)).visibility
        share = 100.0 * float(metrics.penumbra_region(truth).sum()) / truth.size
        rows = {}
        for method, label, params in CONFIGS:
            rows[label] = m = measure(renderer, scene, method, params, truth, args.repeats)
            print(f"| {name} ({share:.1f}% penumbra) | {label} | {m['maps']:.0f} | {m['rmse']:.4f} | {m['ms']:.0f} |", flush=True)
        a, r = rows[CONFIGS[1][1]], rows[CONFIGS[7][1]]
        targets.append((name, share, a["rmse"] / r["rmse"], a["ms"] / r["ms"]))
    print()
    print("| scene | penumbra % | adaptive / reference-289 error | adaptive / reference-289 time | target met |")
    print("|---|---:|---:|---:|---|")
    for name, share, error, time in targets:
        print(f"| {name} | {share:.1f} | {error:.2f} | {time:.2f} | {'yes' if error <= 1.1 and time <= 1 / 3 else 'no'} |")
    print()
    print("| light radius | penumbra pixels (reference-289) | adaptive maps | cells subdivided | max depth reached |")
    print("|---:|---:|---:|---:|---|")
    for radius in (0.02, 0.05, 0.1, 0.2, 0.4, 0.8):
        scene = penumbra.scenes.get("sphere_on_plane", width=args.size, height=args.size, light_radius=radius)
        v = renderer.render(scene, "reference", n_samples=289, sampling="disk", jitter=False, map_size=512).visibility
        pixels = int(metrics.penumbra_region(v).sum())
        s = renderer.render(scene, "adaptive").stats
        print(f"| {radius} | {pixels} | {s['shadow_maps_rendered']} | {s['cells_subdivided']} | {'yes' if s['max_depth_reached'] else 'no'} |", flush=True)


if __name__ == "__main__":
    main()

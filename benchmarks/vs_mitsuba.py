"""Where the CPU ray tracer wins (issue 24): `hard` and `pcss` against
Mitsuba 3 on the CPU, on one scene, in one run, interleaved.

    python3 benchmarks/vs_mitsuba.py [--scene sphere_on_plane] [--size 128] [--rounds 5]

Per configuration: the median wall time of `--rounds` renders (penumbra:
visibility only, warm renderer, no pass cache, all passes in one
submission; Mitsuba: `ground_truth(cache=False)` of the visibility, the
time of its render call with the scene already exported, JIT kernels warm
after the first), and the penumbra RMSE against Mitsuba at 1024 spp.
Rounds alternate between the two so that load on the machine hits both.
The last lines give the ratios the README quotes: `hard` over Mitsuba at
4 spp, and `pcss` against Mitsuba at the sample count whose error is
nearest to `pcss`'s.
"""

from __future__ import annotations

import argparse
import statistics
import sys

import penumbra
from penumbra import metrics
from penumbra import mitsuba as pm

CONFIGS = [
    ("hard", {}),
    ("hard", {"map_size": "auto"}),
    ("hard", {"map_size": 512}),
    ("pcss", {}),
    ("pcss", {"map_size": "auto"}),
]
SPPS = [1, 2, 4, 8, 16, 64]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default="sphere_on_plane")
    parser.add_argument("--size", type=int, default=128)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args(argv)
    scene = penumbra.scenes.get(args.scene, width=args.size, height=args.size)
    gt = pm.ground_truth(scene, spp=1024, kinds=("visibility",), noise_seed=1)
    region = metrics.penumbra_region(gt.visibility)
    r = penumbra.Renderer(pass_cache=False)
    times: dict[str, list[float]] = {}
    errors: dict[str, float] = {}
    for method, params in CONFIGS:  # warm-up: pipelines, driver compiles
        r.render(scene, method, outputs=["visibility"], **params)
    pm.ground_truth(scene, spp=4, seed=2, kinds=["visibility"], cache=False)
    for _ in range(args.rounds):
        for method, params in CONFIGS:
            key = f"{method} {' '.join(f'{k}={v}' for k, v in params.items()) or '(defaults)'}"
            result = r.render(scene, method, outputs=["visibility"], **params)
            times.setdefault(key, []).append(result.total_ms)
            errors[key] = metrics.rmse(result.visibility, gt.visibility, region)
        for spp in SPPS:
            key = f"mitsuba {spp} spp"
            peer = pm.ground_truth(scene, spp=spp, seed=2, kinds=["visibility"], cache=False)
            times.setdefault(key, []).append(peer.seconds["visibility"] * 1e3)
            errors[key] = metrics.rmse(peer.images["visibility"], gt.visibility, region)
    ms = {k: statistics.median(v) for k, v in times.items()}
    print(f"{args.scene} {args.size}x{args.size}; adapter {r.adapter_info['name']}; Mitsuba {gt.variant}; medians of {args.rounds} interleaved rounds")
    print("| configuration | ms | penumbra RMSE |")
    print("|---|---|---|")
    for k in ms:
        print(f"| {k} | {ms[k]:.1f} | {errors[k]:.4f} |")
    m4 = ms["mitsuba 4 spp"]
    print(f"\nhard (defaults) / mitsuba 4 spp: {ms['hard (defaults)'] / m4:.2f}; hard map_size=auto / mitsuba 4 spp: {ms['hard map_size=auto'] / m4:.2f}")
    for key in ("pcss (defaults)", "pcss map_size=auto"):
        peer = min((k for k in ms if k.startswith("mitsuba")), key=lambda k: abs(errors[k] - errors[key]))
        print(f"{key}: RMSE {errors[key]:.4f} in {ms[key]:.1f} ms; Mitsuba nearest in error: {peer} (RMSE {errors[peer]:.4f}) "
              f"in {ms[peer]:.1f} ms: pcss / mitsuba = {ms[key] / ms[peer]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

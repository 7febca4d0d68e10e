"""Render time of two builds of penumbra, in one run, alternating.

Each round runs this script's `--worker` once per build, A then B, in a
fresh process whose `PYTHONPATH` puts that build's `python/` folder first;
a worker times, per method at its defaults (`pass_cache=False`, CPU clocks),
the median wall time of repeated renders of each scene (`--scenes`, default
`sphere_on_plane`; any name `penumbra.scenes.get` takes, e.g.
`generated:38`) at each size, for every method or those of `--methods`,
and the rate of a 64x64 sweep of late parameters on one cached renderer
(pvmf's `n_blur`, pcss's `seed`, hard's `constant_bias`). The report gives
each figure's median over rounds for A and B and the median of the per-round
ratios B/A (below 1: B is faster).

    python benchmarks/ab_render_time.py --a /path/to/old/python --b python --rounds 5
    python benchmarks/ab_render_time.py --a OLD/python --b python --scenes generated:1 generated:38 \
        --methods hard adaptive --sizes 96 --no-map-size-auto --rounds 2 --repeats 2

Build A's extension in place first (e.g. `maturin build --release` in a
worktree of the old commit, then unpack the wheel's `_core.abi3.so` into its
`python/penumbra/`).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

PARAMS: dict[str, dict] = {"reference": {"n_samples": 16}, "raytraced": {"n_samples": 16}, "triangle_masks": {"n_samples": 16}}


def median_ms(renderer, scene, method: str, params: dict, repeats: int) -> float | None:
    """The median wall time in ms of `repeats` renders after a first one, or
    None (said on stderr) where the method refuses the render."""
    import penumbra

    try:
        renderer.render(scene, method, **params)
    except penumbra.PenumbraError as e:
        print(f"{method} {params} {scene.camera.width}px: {e}", file=sys.stderr)
        return None
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        renderer.render(scene, method, **params)
        times.append(time.perf_counter() - t)
    return 1e3 * statistics.median(times)


def worker(sizes: list[int], repeats: int, scenes: list[str], methods: list[str] | None, auto: bool) -> dict[str, float]:
    import penumbra

    out: dict[str, float] = {}
    renderer = penumbra.Renderer(timing="cpu", pass_cache=False)
    for name, size in [(n, z) for n in scenes for z in sizes]:
        scene = penumbra.scenes.get(name, width=size, height=size)
        where = "" if name == "sphere_on_plane" else f"{name} "
        for method in methods or penumbra.methods():  # the registry of the build under test
            params = PARAMS.get(method, {})
            ms = median_ms(renderer, scene, method, params, repeats)
            if ms is None:  # e.g. a method that refuses this size
                continue
            out[f"{where}{method} {size}px ms"] = ms
            if auto and "map_size" in penumbra.method_info(method).defaults() and penumbra.method_info(method).param("map_size").choices:
                # A build with map_size="auto" (issue 24): the same, sized to the image.
                ms = median_ms(renderer, scene, method, {**params, "map_size": "auto"}, repeats)
                if ms is None:  # adaptive's grid of 4096-texel maps is refused
                    continue
                out[f"{where}{method} map_size=auto {size}px ms"] = ms
    cached = penumbra.Renderer(timing="cpu")
    scene = penumbra.scenes.get("sphere_on_plane", width=64, height=64)
    sweep = [("pvmf", {"n_blur": n}) for n in range(0, 24, 2)]
    sweep += [("pcss", {"seed": s}) for s in range(12)]
    sweep += [("hard", {"constant_bias": 0.25 + 0.05 * i}) for i in range(12)]
    for method, params in sweep[:3]:
        cached.render(scene, method, **params)
    t = time.perf_counter()
    for method, params in sweep:
        cached.render(scene, method, **params)
    out["sweep 64px renders/s"] = len(sweep) / (time.perf_counter() - t)
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--a", help="build A's python/ folder")
    parser.add_argument("--b", help="build B's python/ folder")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--sizes", type=int, nargs="*", default=[64, 256])
    parser.add_argument("--scenes", nargs="*", default=["sphere_on_plane"], help="scene names (penumbra.scenes.get)")
    parser.add_argument("--methods", nargs="*", help="methods (default: every one of the build under test)")
    parser.add_argument("--map-size-auto", action=argparse.BooleanOptionalAction, default=True, help="also time map_size=\"auto\"")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        print(json.dumps(worker(args.sizes, args.repeats, args.scenes, args.methods, args.map_size_auto)))
        return 0
    runs: dict[str, list[dict[str, float]]] = {"A": [], "B": []}
    for r in range(args.rounds):
        for name, path in (("A", args.a), ("B", args.b)):
            env = dict(os.environ, PYTHONPATH=os.path.abspath(path))
            env.setdefault("XDG_RUNTIME_DIR", "/tmp")
            cmd = [sys.executable, __file__, "--worker", "--repeats", str(args.repeats), "--sizes", *map(str, args.sizes), "--scenes", *args.scenes]
            cmd += ["--methods", *args.methods] if args.methods else []
            cmd += [] if args.map_size_auto else ["--no-map-size-auto"]
            done = subprocess.run(cmd, env=env, capture_output=True, text=True)
            if done.returncode != 0:
                sys.exit(f"build {name}'s worker failed:\n{done.stderr}")
            runs[name].append(json.loads(done.stdout.strip().splitlines()[-1]))
        print(f"round {r + 1}/{args.rounds} done", file=sys.stderr)
    print(f"| figure | A ({args.a}) | B ({args.b}) | B/A (median of {args.rounds} rounds) |")
    print("|---|---|---|---|")
    for key in runs["B"][0]:
        b = [run[key] for run in runs["B"]]
        if key not in runs["A"][0]:
            print(f"| {key} | (not in A) | {statistics.median(b):.2f} | |")
            continue
        a = [run[key] for run in runs["A"]]
        ratio = statistics.median(y / x for x, y in zip(a, b))
        print(f"| {key} | {statistics.median(a):.2f} | {statistics.median(b):.2f} | {ratio:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())

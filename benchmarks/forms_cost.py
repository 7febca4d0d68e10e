"""Warm render time of a mesh handed over as a triangle soup against the
welded mesh, every method (docs/connectivity.md, issue 27): interleaved
rounds in one process, no pass cache, so a shared machine's drift weighs on
both alike.

    python3 benchmarks/forms_cost.py [--size 128] [--rounds 5] [MESH ...]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import penumbra
from penumbra import forms, scenes

PARAMS = {"reference": {"n_samples": 64}, "raytraced": {"n_samples": 16}, "triangle_masks": {"n_samples": 64}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    root = scenes.meshes_folder()
    shared = [str(root / m) for m in ("spot.obj", "corpus/cat-low-resolution.obj")] if root is not None else []
    parser.add_argument("meshes", nargs="*", default=shared, help="mesh files (default: spot and the low-resolution cat of the shared meshes)")
    parser.add_argument("--size", type=int, default=128)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    if not args.meshes:
        parser.error("no MESH given and the shared meshes are absent (set PENUMBRA_MESHES)")
    renderer = penumbra.Renderer(pass_cache=False)
    print("| mesh | method | welded ms | soup ms | soup / welded |\n|---|---|---|---|---|")
    for path in args.meshes:
        welded = scenes.from_mesh(path, width=args.size, height=args.size, light_radius=0.45)
        soup = forms.replace_mesh(welded, 1, forms.soup(welded.meshes[1]))
        for method in penumbra.methods():
            params = PARAMS.get(method, {})
            try:
                renderer.render(welded, method, **params)
                renderer.render(soup, method, **params)
            except penumbra.GpuFeatureError:
                continue
            times: dict[str, list[float]] = {"welded": [], "soup": []}
            for _ in range(args.rounds):
                for name, scene in (("welded", welded), ("soup", soup)):
                    start = time.perf_counter()
                    renderer.render(scene, method, **params)
                    times[name].append(time.perf_counter() - start)
            w, s = (statistics.median(times[k]) * 1000 for k in ("welded", "soup"))
            print(f"| {Path(path).name} | {method} | {w:.1f} | {s:.1f} | {s / w:.2f} |", flush=True)


if __name__ == "__main__":
    main()

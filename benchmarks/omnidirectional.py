"""Omnidirectional shadow maps (issue 17): cube faces against the fitted
frustum, and every method on scenes one frustum cannot cover.

1. Seams: on every built-in scene (where one frustum covers the geometry),
   each method rendered with `projection="cube"` against `"frustum"` at the
   same `map_size`, beside the frustum's own resolution error (the frustum
   at `map_size` against four times that) and, for the methods that jitter
   their taps, their sampling noise (seed 0 against seed 1); then both
   projections' penumbra error against Mitsuba, and the largest difference
   over pixels within two texels of a cube face boundary.
2. Cost: `cube` against `frustum` render time in one run (renders
   alternating, median), with the faces rendered.
3. Against Mitsuba: every method on the wide floor (with spot.obj), the
   Cornell box and, with --sponza, Sponza: penumbra RMSE beside the ground
   truth's noise, stray pixels, and time as a ratio to `hard`.
4. `reference` at 1024 samples on the wide floor against the convergence
   criterion of the built-in scenes (benchmarks/reference_convergence.py):
   2 x ground-truth noise + the resolution error (its 4096 map against 2048).

    python benchmarks/omnidirectional.py [--size 128] [--spp 1024] [--sponza] [--parts 1 2 3 4]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

import penumbra
from penumbra import metrics
from penumbra import mitsuba as pm

MESHES = Path(__file__).resolve().parents[2] / "shared" / "meshes"
FAST = {"reference": {"n_samples": 64}}


def seam_band(result: penumbra.RenderResult, light: np.ndarray, map_size: int, texels: float = 2.0) -> np.ndarray:
    """Geometry pixels whose direction from the light lies within `texels`
    texels of a cube face boundary (face coordinates span 2 / map_size per texel)."""
    d = np.abs(result.position - light)
    largest = d.max(axis=-1)
    second = np.sort(d, axis=-1)[..., 1]
    with np.errstate(invalid="ignore", divide="ignore"):
        near = 1.0 - second / largest < texels * 2.0 / map_size
    return near & (result.object_id >= 0)


def part_seams(renderer: penumbra.Renderer, size: int, map_size: int, spp: int) -> None:
    print(f"\n## Cube faces against the fitted frustum ({size}x{size}, map_size {map_size}, ground truth {spp} spp)\n")
    print(
        "| scene | method | cube vs frustum | frustum resolution error | sampling noise | "
        "penumbra RMSE frustum | penumbra RMSE cube | max diff at seams (pixels) |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for name in penumbra.scenes.names():
        scene = penumbra.scenes.get(name, width=size, height=size)
        gt = pm.ground_truth(scene, spp=spp, kinds=["visibility"])
        region = metrics.penumbra_region(gt.visibility)
        light = np.asarray(scene.light.center, dtype=np.float32)
        for method in penumbra.methods():
            extra = {**FAST.get(method, {}), **({"open_edges": "silhouette"} if method in ("pvm", "pvmf") else {})}
            frustum = renderer.render(scene, method, projection="frustum", map_size=map_size, **extra)
            finer = renderer.render(scene, method, projection="frustum", map_size=4 * map_size, **extra)
            cube = renderer.render(scene, method, projection="cube", map_size=map_size, **extra)
            geo = frustum.object_id >= 0
            e_cube = metrics.rmse(cube.visibility, frustum.visibility, geo)
            e_res = metrics.rmse(finer.visibility, frustum.visibility, geo)
            noise = ""
            if "seed" in frustum.params and method != "reference":
                other = renderer.render(scene, method, projection="frustum", map_size=map_size, seed=1, **extra)
                noise = f"{metrics.rmse(other.visibility, frustum.visibility, geo):.4f}"
            band = seam_band(cube, light, map_size)
            at_seams = float(np.abs(cube.visibility - frustum.visibility)[band].max()) if band.any() else 0.0
            truth = [metrics.rmse(r.visibility, gt.visibility, region) for r in (frustum, cube)]
            print(
                f"| {name} | {method} | {e_cube:.4f} | {e_res:.4f} | {noise} | {truth[0]:.4f} | {truth[1]:.4f} | "
                f"{at_seams:.3f} ({int(band.sum())}) |",
                flush=True,
            )


def part_cost(renderer: penumbra.Renderer, size: int, map_size: int, repeats: int = 5) -> None:
    print(f"\n## Cost of cube faces ({size}x{size}, map_size {map_size} per face; median of {repeats}, alternating)\n")
    print("| scene | method | frustum ms | cube ms | cube / frustum | faces rendered (skipped) |")
    print("|---|---|---|---|---|---|")
    for name in penumbra.scenes.names():
        scene = penumbra.scenes.get(name, width=size, height=size)
        for method in penumbra.methods():
            extra = {**FAST.get(method, {}), **({"open_edges": "silhouette"} if method in ("pvm", "pvmf") else {})}
            times: dict[str, list[float]] = {"frustum": [], "cube": []}
            faces = 0
            for mode in ("frustum", "cube") * (repeats + 1):
                t = time.perf_counter()
                result = renderer.render(scene, method, projection=mode, map_size=map_size, **extra)
                times[mode].append(time.perf_counter() - t)
                if mode == "cube":
                    faces = result.stats["shadow_map_faces"]
                    if method == "reference":
                        faces = f"{faces} in {result.stats['cube_maps']} maps"  # type: ignore[assignment]
            f, c = (1e3 * statistics.median(times[m][1:]) for m in ("frustum", "cube"))
            skipped = "" if method == "reference" else f" ({6 - int(faces)})"
            print(f"| {name} | {method} | {f:.1f} | {c:.1f} | {c / f:.2f} | {faces}{skipped} |", flush=True)


def wide_scenes(size: int, sponza: bool) -> dict[str, penumbra.Scene]:
    out = {
        "wide floor (spot.obj)": penumbra.scenes.wide_floor(str(MESHES / "spot.obj"), width=size, height=size),
        "Cornell box": penumbra.scenes.cornell_box(str(MESHES / "CornellBox-Original.obj"), width=size, height=size),
    }
    if sponza:
        out["Sponza"] = penumbra.scenes.sponza(str(MESHES / "sponza.obj"), width=size, height=size)
    return out


def part_truth(renderer: penumbra.Renderer, size: int, spp: int, sponza: bool) -> None:
    print(f"\n## Every method against Mitsuba where one frustum cannot cover the scene ({size}x{size}, {spp} spp)\n")
    print("| scene | method | penumbra RMSE | ground-truth noise | stray pixels | faces | time / hard |")
    print("|---|---|---|---|---|---|---|")
    for name, scene in wide_scenes(size, sponza).items():
        gt = pm.ground_truth(scene, spp=spp, noise_seed=1, kinds=["visibility"])
        region = metrics.penumbra_region(gt.visibility)
        noise = metrics.rmse(gt.visibility, gt.second.visibility, region) / np.sqrt(2)
        hard_ms = None
        for method in penumbra.methods():
            params = {"n_samples": 256} if method == "reference" else {}
            try:
                renderer.render(scene, method, **params)
                t = time.perf_counter()
                result = renderer.render(scene, method, **params)
                ms = 1e3 * (time.perf_counter() - t)
            except penumbra.PenumbraError as e:
                print(f"| {name} | {method} | refused: {type(e).__name__}: {str(e)[:90]} | | | | |", flush=True)
                continue
            hard_ms = hard_ms or ms
            geo = result.object_id >= 0
            stray = ((gt.visibility >= 0.98) & (result.visibility < 0.5)) | ((gt.visibility <= 0.02) & (result.visibility > 0.5))
            print(
                f"| {name} | {method}{' (256)' if method == 'reference' else ''} | {metrics.rmse(result.visibility, gt.visibility, region):.4f} | "
                f"{noise:.4f} | {100 * np.mean(stray[geo]):.2f}% | {result.stats.get('shadow_map_faces', '')} | {ms / hard_ms:.1f} |",
                flush=True,
            )


def part_reference(renderer: penumbra.Renderer, size: int, spp: int) -> None:
    print(f"\n## `reference` at 1024 samples on the wide floor ({size}x{size}, {spp} spp)\n")
    scene = penumbra.scenes.wide_floor(str(MESHES / "spot.obj"), width=size, height=size)
    gt = pm.ground_truth(scene, spp=spp, noise_seed=1, kinds=["visibility"])
    region = metrics.penumbra_region(gt.visibility)
    noise = metrics.rmse(gt.visibility, gt.second.visibility, region) / np.sqrt(2)
    result = renderer.render(scene, "reference", n_samples=1024)
    finer = renderer.render(scene, "reference", n_samples=1024, map_size=4096)
    error = metrics.rmse(result.visibility, gt.visibility, region)
    resolution = metrics.rmse(result.visibility, finer.visibility, region)
    criterion = 2 * noise + resolution
    print("| penumbra RMSE | ground-truth noise | resolution error | criterion | met | cube maps |")
    print("|---|---|---|---|---|---|")
    print(f"| {error:.4f} | {noise:.4f} | {resolution:.4f} | {criterion:.4f} | {'yes' if error <= criterion else 'no'} | {result.stats['cube_maps']} of {result.stats['light_samples']} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=128)
    parser.add_argument("--map-size", type=int, default=1024)
    parser.add_argument("--spp", type=int, default=1024)
    parser.add_argument("--sponza", action="store_true")
    parser.add_argument("--parts", type=int, nargs="+", default=[1, 2, 3, 4])
    args = parser.parse_args()
    renderer = penumbra.Renderer(timing="cpu", pass_cache=False)
    if 1 in args.parts:
        part_seams(renderer, args.size, args.map_size, args.spp)
    if 2 in args.parts:
        part_cost(renderer, args.size, args.map_size)
    if 3 in args.parts:
        part_truth(renderer, args.size, args.spp, args.sponza)
    if 4 in args.parts:
        part_reference(renderer, args.size, args.spp)


if __name__ == "__main__":
    main()

"""Omnidirectional shadow maps (issue 17): cube faces against the fitted
frustum where both apply.

Seams: on every built-in scene (where one frustum covers the geometry),
each method rendered with `projection="cube"` against `"frustum"` at the
same `map_size`, beside the frustum's own resolution error (the frustum at
`map_size` against four times that) and, for the methods that jitter their
taps, their sampling noise (seed 0 against seed 1); then both projections'
penumbra error against Mitsuba, and the largest difference over pixels
within two texels of a cube face boundary.

    python benchmarks/omnidirectional.py [--size 128] [--map-size 1024] [--spp 1024]

The cost of cube faces, and every method against Mitsuba on the wide floor,
the Cornell box and Sponza: `penumbra bench --config
benchmarks/omnidirectional.toml`; `reference` at 1024 samples on the wide
floor against the convergence criterion: `penumbra bench --config
benchmarks/reference_convergence.toml --set 'scenes=["wide_floor:spot.obj"]'
--set ground_truth_spp=1024 --set 'large={}'`.
"""

from __future__ import annotations

import argparse

import numpy as np

import penumbra
from penumbra import metrics
from penumbra import mitsuba as pm

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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=128)
    parser.add_argument("--map-size", type=int, default=1024)
    parser.add_argument("--spp", type=int, default=1024)
    args = parser.parse_args()
    renderer = penumbra.Renderer(timing="cpu", pass_cache=False)
    part_seams(renderer, args.size, args.map_size, args.spp)


if __name__ == "__main__":
    main()

"""Shadow-map bias schemes of method `hard` against exact ray casting.

For every built-in scene, and two thin closed plates (2 x t x 2 boxes at
y = 0.5, t = 1e-4 and 1e-3: issue 22's case for `second_depth`), with a
point light (radius 0), renders `hard` with
each bias scheme and map size, casts a ray from every pixel's surface point
to the light on the CPU, and counts the pixels where they disagree:
- acne: shadowed by the method, lit in truth;
- leak: lit by the method, shadowed in truth;
each split into those on the one-pixel band around the true shadow outline
(resolution, not bias) and those beyond it (the bias's fault).

    python benchmarks/bias_study.py [--size 256]
"""

from __future__ import annotations

import argparse

import numpy as np

import penumbra
from penumbra.raycast import outline_band, point_light_visibility


def disagreement(result: penumbra.RenderResult, exact: np.ndarray) -> dict[str, int]:
    geometry = result.object_id >= 0
    lit_truth = exact > 0.5
    lit_method = result.visibility > 0.5
    band = outline_band(lit_truth)
    acne = geometry & lit_truth & ~lit_method
    leak = geometry & ~lit_truth & lit_method
    return {
        "acne": int((acne & ~band).sum()),
        "leak": int((leak & ~band).sum()),
        "acne_on_outline": int((acne & band).sum()),
        "leak_on_outline": int((leak & band).sum()),
        "pixels": int(geometry.sum()),
    }


def exact_visibility(scene: penumbra.Scene, result: penumbra.RenderResult) -> np.ndarray:
    geometry = result.object_id >= 0
    exact = np.zeros(geometry.shape)
    exact[geometry] = point_light_visibility(scene, result.position[geometry], result.normal[geometry])
    return exact


def thin_plate(thickness: float, size: int) -> penumbra.Scene:
    """A closed plate 2 x thickness x 2 at y = 0.5 over the ground slab, with
    the default scene's point light and camera: its top face is lit."""
    base = penumbra.scenes.get(width=size, height=size, light_radius=0.0)
    plate = penumbra.scenes.box((0.0, 0.5, 0.0), (2.0, thickness, 2.0), name="plate")
    return penumbra.Scene([penumbra.scenes.ground_slab(), plate], base.light, base.camera, name=f"thin_plate_{thickness:g}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--map-sizes", type=int, nargs="+", default=[512, 2048])
    args = parser.parse_args()
    renderer = penumbra.Renderer()
    print(f"adapter: {renderer.adapter_info['name']}; image {args.size}x{args.size}; light radius 0\n")
    print("| scene | map_size | bias | acne | leak | acne on outline | leak on outline | geometry pixels |")
    print("|---|---|---|---|---|---|---|---|")
    scenes = [(n, penumbra.scenes.get(n, width=args.size, height=args.size, light_radius=0.0)) for n in penumbra.scenes.names()]
    scenes += [(f"thin_plate t={t:g}", thin_plate(t, args.size)) for t in (1e-4, 1e-3)]
    for name, scene in scenes:
        exact = None
        for map_size in args.map_sizes:
            for bias in ("slope", "second_depth", "midpoint", "none"):
                result = renderer.render(scene, map_size=map_size, bias=bias)
                if exact is None:
                    exact = exact_visibility(scene, result)
                d = disagreement(result, exact)
                print(f"| {name} | {map_size} | {bias} | {d['acne']} | {d['leak']} | {d['acne_on_outline']} | {d['leak_on_outline']} | {d['pixels']} |")


if __name__ == "__main__":
    main()

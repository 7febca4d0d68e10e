"""`hard`'s bias schemes with a point light against exact ray casting on
the CPU (`penumbra.raycast.point_light_errors`): acne (shadowed by the
method, lit in truth) and leaks (the reverse), beyond and on the one-pixel
band around the true shadow outline (resolution, not bias), per setting
(docs/methods/hard.md): every built-in scene and two thin closed plates
(2 x t x 2 boxes at y = 0.5, t = 1e-4 and 1e-3: issue 22's case for
`second_depth`), each bias scheme at map sizes 512 and 2048. The ray
caster's truth is computed once per scene. (`raytraced`'s ray offsets, the
same comparison: `penumbra bench --config benchmarks/ray_offsets.toml`.)

    python benchmarks/point_light.py [--size 256]
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

import penumbra
from penumbra.raycast import point_light_errors, point_light_visibility


def thin_plate(thickness: float, size: int) -> penumbra.Scene:
    """A closed plate 2 x thickness x 2 at y = 0.5 over the ground slab, with the default scene's point light and camera."""
    base = penumbra.scenes.get(width=size, height=size, light_radius=0.0)
    plate = penumbra.scenes.box((0.0, 0.5, 0.0), (2.0, thickness, 2.0), name="plate")
    return penumbra.Scene([penumbra.scenes.ground_slab(), plate], base.light, base.camera, name=f"thin_plate_{thickness:g}")


def disagreement(renderer: penumbra.Renderer, scenes: dict[str, penumbra.Scene], method: str, settings: list[dict[str, Any]]) -> None:
    print("| scene | settings | acne | leak | acne on outline | leak on outline | geometry pixels |\n|---|---|---|---|---|---|---|")
    for name, scene in scenes.items():
        exact = None
        for params in settings:
            result = renderer.render(scene, method, **params)
            geometry = result.object_id >= 0
            if exact is None:  # once per scene: every setting has the same G-buffer
                exact = np.zeros(geometry.shape, dtype=bool)
                exact[geometry] = point_light_visibility(scene, result.position[geometry], result.normal[geometry]) > 0.5
            e = point_light_errors(result, scene, exact)
            shown = ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in params.items())
            print(f"| {name} | {shown} | " + " | ".join(f"{e[k]:.0f}" for k in ("acne", "leak", "acne_on_outline", "leak_on_outline", "geometry_pixels")) + " |", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=256)
    args = parser.parse_args()
    renderer = penumbra.Renderer()
    print(f"adapter: {renderer.adapter_info['name']} ({renderer.adapter_info['driver_info']}); {args.size}x{args.size}; light radius 0\n")
    scenes = {n: penumbra.scenes.get(n, width=args.size, height=args.size, light_radius=0.0) for n in penumbra.scenes.names()}
    scenes.update({f"thin_plate t={t:g}": thin_plate(t, args.size) for t in (1e-4, 1e-3)})
    disagreement(renderer, scenes, "hard", [{"map_size": m, "bias": b} for m in (512, 2048) for b in ("slope", "second_depth", "midpoint", "none")])


if __name__ == "__main__":
    main()

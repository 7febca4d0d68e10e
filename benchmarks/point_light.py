"""Shadow tests with a point light against exact ray casting on the CPU
(`penumbra.raycast.point_light_visibility`): acne (shadowed by the method,
lit in truth) and leaks (the reverse), beyond and on the one-pixel band
around the true shadow outline (resolution, not bias), per setting.

    python benchmarks/point_light.py bias [--size 256]        # hard's bias schemes (docs/methods/hard.md)
    python benchmarks/point_light.py offsets [--size 128]     # raytraced's ray offsets (docs/methods/raytraced.md)

`bias`: every built-in scene and two thin closed plates (2 x t x 2 boxes at
y = 0.5, t = 1e-4 and 1e-3: issue 22's case for `second_depth`), each bias
scheme at map sizes 512 and 2048. `offsets`: every built-in scene and the
real meshes (cube, spot, teapot, the small bunny, the Cornell box), several
ray-origin offsets.
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

import penumbra
from penumbra.raycast import outline_band, point_light_visibility


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
            if exact is None:
                exact = np.zeros(geometry.shape, dtype=bool)
                exact[geometry] = point_light_visibility(scene, result.position[geometry], result.normal[geometry]) > 0.5
            lit, band = result.visibility > 0.5, outline_band(exact)
            acne, leak = geometry & exact & ~lit, geometry & ~exact & lit
            shown = ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in params.items())
            print(f"| {name} | {shown} | {(acne & ~band).sum()} | {(leak & ~band).sum()} | {(acne & band).sum()} | {(leak & band).sum()} | {geometry.sum()} |", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("what", choices=["bias", "offsets"])
    parser.add_argument("--size", type=int, help="image side (default 256 for bias, 128 for offsets)")
    args = parser.parse_args()
    size = args.size or (256 if args.what == "bias" else 128)
    renderer = penumbra.Renderer()
    print(f"adapter: {renderer.adapter_info['name']} ({renderer.adapter_info['driver_info']}); {size}x{size}; light radius 0\n")
    scenes = {n: penumbra.scenes.get(n, width=size, height=size, light_radius=0.0) for n in penumbra.scenes.names()}
    if args.what == "bias":
        scenes.update({f"thin_plate t={t:g}": thin_plate(t, size) for t in (1e-4, 1e-3)})
        disagreement(renderer, scenes, "hard", [{"map_size": m, "bias": b} for m in (512, 2048) for b in ("slope", "second_depth", "midpoint", "none")])
        return
    root = penumbra.scenes.meshes_folder()
    if root is not None:  # the meshes placed as from_mesh's default, and the Cornell box
        scenes.update({m: penumbra.scenes.from_mesh(str(root / m), width=size, height=size, light_radius=0.0)
                       for m in ("cube.obj", "spot.obj", "teapot-mcguire-closed.obj", "bun_zipper_res4.ply")})
        scenes["CornellBox-Original.obj"] = penumbra.scenes.get("cornell_box", width=size, height=size, light_radius=0.0)
    disagreement(renderer, scenes, "raytraced", [{"ray_offset": o} for o in (0.0, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3)])


if __name__ == "__main__":
    main()

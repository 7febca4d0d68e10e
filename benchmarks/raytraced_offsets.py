"""Method `raytraced` with a point light against CPU ray casting
(`penumbra.raycast.point_light_visibility`, the check of `hard`'s bias
scenes), for several ray-origin offsets: acne (shadowed by the method, lit
by the CPU rays) and leaks (the reverse), beyond and on the one-pixel band
around the true shadow outline, on every built-in scene and the real meshes.

    python benchmarks/raytraced_offsets.py [--size 128]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import penumbra
from penumbra.raycast import outline_band, point_light_visibility

MESHES = Path(__file__).resolve().parents[1] / ".." / "shared" / "meshes"
REAL = ["cube.obj", "spot.obj", "teapot-mcguire-closed.obj", "bun_zipper_res4.ply", "CornellBox-Original.obj"]


def scenes(size: int) -> dict[str, penumbra.Scene]:
    out = {n: penumbra.scenes.get(n, width=size, height=size, light_radius=0.0) for n in penumbra.scenes.names()}
    for name in REAL:
        if (MESHES / name).exists():
            if name.startswith("CornellBox"):
                s = penumbra.scenes.cornell_box(str(MESHES / name), width=size, height=size)
            else:
                s = penumbra.scenes.from_mesh(str(MESHES / name), width=size, height=size)
            out[name] = s.with_light(s.light.with_radius(0.0))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=128)
    parser.add_argument("--offsets", type=float, nargs="+", default=[0.0, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3])
    args = parser.parse_args()
    renderer = penumbra.Renderer()
    print(f"adapter: {renderer.adapter_info['name']} ({renderer.adapter_info['driver_info']}); {args.size}x{args.size}; light radius 0\n")
    print("| scene | ray_offset | acne | leak | acne on outline | leak on outline | geometry pixels |")
    print("|---|---|---|---|---|---|---|")
    for name, scene in scenes(args.size).items():
        exact = None
        for offset in args.offsets:
            result = renderer.render(scene, "raytraced", ray_offset=offset)
            geometry = result.object_id >= 0
            if exact is None:
                exact = np.zeros(geometry.shape, dtype=bool)
                exact[geometry] = point_light_visibility(scene, result.position[geometry], result.normal[geometry]) > 0.5
            lit = result.visibility > 0.5
            band = outline_band(exact)
            acne, leak = geometry & exact & ~lit, geometry & ~exact & lit
            print(f"| {name} | {offset:g} | {(acne & ~band).sum()} | {(leak & ~band).sum()} | {(acne & band).sum()} | {(leak & band).sum()} | {geometry.sum()} |")


if __name__ == "__main__":
    main()

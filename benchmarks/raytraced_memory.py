"""Acceleration structures of method `raytraced`: their memory (the `stats`
the method reports: `acceleration_bytes`, from the device allocator's
report) and their build time (the `acceleration` pass of the first render,
against the same pass once they are cached), per built-in scene and real
mesh, on a fresh renderer.

    python benchmarks/raytraced_memory.py
"""

from __future__ import annotations

from pathlib import Path

import penumbra

MESHES = Path(__file__).resolve().parents[1] / ".." / "shared" / "meshes"
REAL = ["spot.obj", "teapot-mcguire-closed.obj", "bun_zipper.ply", "CornellBox-Original.obj", "sponza.obj"]


def main() -> None:
    renderer = penumbra.Renderer(timing="cpu")
    print(f"adapter: {renderer.adapter_info['name']} ({renderer.adapter_info['driver_info']})\n")
    print("| scene | triangles | acceleration bytes | bytes per triangle | build (ms, first render) | acceleration pass when cached (ms) |")
    print("|---|---|---|---|---|---|")
    scenes = {n: penumbra.scenes.get(n, width=32, height=32) for n in penumbra.scenes.names()}
    for name in REAL:
        if (MESHES / name).exists():
            make = {"CornellBox-Original.obj": penumbra.scenes.cornell_box, "sponza.obj": penumbra.scenes.sponza}.get(name, penumbra.scenes.from_mesh)
            scenes[name] = make(str(MESHES / name), width=32, height=32)
    for name, scene in scenes.items():
        first = renderer.render(scene, "raytraced", n_samples=1)
        again = renderer.render(scene, "raytraced", n_samples=1)
        assert again.stats["blas_built"] == 0
        triangles = first.stats["triangles"]
        b = first.stats["acceleration_bytes"]
        print(f"| {name} | {triangles} | {b} | {b / triangles:.0f} | {first.timings['acceleration']:.1f} | {again.timings['acceleration']:.2f} |")
    print(f"\nheld by the cache after all: {again.stats['acceleration_cache_bytes']} bytes")


if __name__ == "__main__":
    main()

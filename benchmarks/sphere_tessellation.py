"""How to make the default sphere smooth without losing the exact comparison.

Each variant of the default scene's sphere (icosphere subdivisions, flat faces
or the sphere's own normals at the vertices) against Mitsuba ground truth of
the same variant: the angle between neighbouring faces (what faceting the eye
sees); the radiance on the sphere under a point light (`hard`, exact there)
against Mitsuba's, relative RMSE off silhouettes (Penumbra shades each pixel
at its centre, Mitsuba averages the pixel: with flat faces smaller than a
pixel the two see different faces); the penumbra visibility RMSE of
`reference` (the in-engine yardstick, which converges to the ground truth
where shadow-map tests and ray casting agree) over the whole image and over
the sphere's own pixels, that of `pcss`; and the process's CPU time per render
(all threads; lavapipe renders on the CPU, so this is the cost, and it is
steadier than wall clock on a shared machine).

    python3 benchmarks/sphere_tessellation.py [--size 256] [--spp 1024] [--repeats 3]
"""

from __future__ import annotations

import argparse
import resource

import numpy as np
import trimesh

import penumbra
from penumbra import metrics
from penumbra import mitsuba as pm


def cpu_seconds() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def sphere(subdivisions: int, vertex_normals: bool) -> penumbra.Mesh:
    m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    v = np.asarray(m.vertices, dtype=np.float64)
    normals = v / np.linalg.norm(v, axis=1, keepdims=True) if vertex_normals else None
    return penumbra.Mesh(v + (0.0, 1.6, 0.0), m.faces, albedo=0.7, object_id=1, normals=normals, name="sphere")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--spp", type=int, default=1024)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    renderer = penumbra.Renderer(pass_cache=False)
    base = penumbra.scenes.get(width=args.size, height=args.size)
    print(f"adapter {renderer.adapter_info['name']}; sphere_on_plane at {args.size}x{args.size}; ground truth Mitsuba {pm.variant()} "
          f"at {args.spp} spp; CPU ms: process CPU time per render, mean of {args.repeats} after a warm-up\n")
    print("| sphere | faces | neighbouring faces (degrees) | sphere radiance RMSE (rel.) | reference penumbra RMSE | on the sphere | pcss penumbra RMSE | ground-truth noise | hard CPU ms | reference CPU ms |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for subdivisions, smooth in ((4, False), (4, True), (5, False), (5, True), (6, False)):
        ball = sphere(subdivisions, smooth)
        scene = penumbra.Scene([base.meshes[0], ball], base.light, base.camera, name="sphere_on_plane")
        point = scene.with_light(scene.light.with_radius(0.0))
        shaded = renderer.render(point, "hard")
        truth = pm.ground_truth(point, spp=64, kinds=["radiance"]).radiance
        keep = (shaded.object_id == 1) & ~metrics.silhouette_band(shaded.object_id)
        radiance = metrics.rmse(shaded.radiance, truth, keep) / float(truth[keep & (shaded.visibility == 1)].mean())
        gt = pm.ground_truth(scene, spp=args.spp, noise_seed=1)
        region = metrics.penumbra_region(gt.visibility)
        row = {}
        for method in ("hard", "pcss", "reference"):
            renderer.render(scene, method)
            start = cpu_seconds()
            for _ in range(args.repeats):
                result = renderer.render(scene, method)
            row[f"{method}_cpu"] = (cpu_seconds() - start) / args.repeats * 1e3
            m = metrics.compare(result, gt)
            row[method] = m["visibility_rmse_penumbra"]
            row["noise"] = m["noise_visibility_rmse_penumbra"]
            on_sphere = region & (result.object_id == 1)
            row[f"{method}_sphere"] = metrics.rmse(result.visibility, gt.visibility, on_sphere)
        angles = np.degrees(trimesh.Trimesh(ball.vertices, ball.faces, process=False).face_adjacency_angles)
        label = f"{subdivisions} subdivisions, {'vertex normals' if smooth else 'flat faces'}"
        print(
            f"| {label} | {len(ball.faces)} | {angles.min():.1f}-{angles.max():.1f} | {radiance:.4f} | {row['reference']:.4f} | {row['reference_sphere']:.4f} | "
            f"{row['pcss']:.4f} | {row['noise']:.4f} | {row['hard_cpu']:.0f} | {row['reference_cpu']:.0f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()

"""Penumbra wedges (issue 19) measured: the numbers and pictures of
docs/methods/wedges.md, from one command.

1. Every built-in scene and every real-mesh scene (the closed-mesh suite of
   `penumbra.scenes.real_mesh_suite` and the open / non-manifold meshes seen
   close) against Mitsuba visibility ground truth, `wedges` beside `pvm`,
   `pvmf` (docs/real_meshes.md's recommended settings) and `pcss`: penumbra
   RMSE (pixels whose true visibility is strictly inside (0.02, 0.98)),
   stray % (`metrics.stray_pixels`: fully lit in truth and darkened below
   0.5, or umbra in truth and lit above 0.5, per cent of such pixels), time
   as the median of `--repeats` renders after a warm-up with every pass
   recomputed, over `hard`'s in the same run.
2. One long box edge over a plane: wedges' Eq. 1-3 interpolation against
   the exact fraction of the disk the plane through the edge and the pixel
   cuts (pvm's disk cut, Cournia Eq. 4.1), over the edge's penumbra.
3. `acute_wedges` on a thin triangular caster (a 23-degree tip; the
   paper's Figure 7), against Mitsuba.
4. `repairs` levels on the real-mesh scenes.
5. With --images: docs/images/wedges_limits.png (the paper's section 8
   limitations: overlapping wedges of two casters summed, and one
   silhouette for a large light).

    python benchmarks/wedges.py [--size 96] [--spp 256] [--repeats 3] [--meshes ../shared/meshes] [--images docs/images]
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path
from typing import Any

import numpy as np
import trimesh

import penumbra
from penumbra import metrics
from penumbra import mitsuba as pm
from penumbra.scenes import box, ground_slab

MESHES = Path(__file__).resolve().parents[1] / ".." / "shared" / "meshes"
OPEN_MESHES = ("bun_zipper_res4.ply", "CornellBox-Original.obj")
PVMF_RECOMMENDED: dict[str, Any] = {"kernel": "disk", "n_blur": 0, "offsets": "radius", "umbra": "skip", "s_e": 0.02}

CONFIGS: list[tuple[str, dict[str, Any]]] = [
    ("hard", {}),
    ("pcss", {}),
    ("pvm", {}),
    ("pvmf", PVMF_RECOMMENDED),
    ("wedges", {}),
    ("wedges", {"falloff": True}),
    ("wedges", {"hard_term": "lit_side"}),
    ("wedges", {"repairs": "none"}),
]
LEVELS = ["none", "hidden", "cone+hidden", "all"]


def shown(method: str, params: dict[str, Any]) -> str:
    if method == "pvmf" and params == PVMF_RECOMMENDED:
        return "recommended"
    return ", ".join(f"{k}={v}" for k, v in params.items()) or "defaults"


def measure(renderer: penumbra.Renderer, scene: penumbra.Scene, method: str, params: dict[str, Any], truth: np.ndarray, repeats: int) -> dict[str, float]:
    result = renderer.render(scene, method, **params)
    times = []
    for _ in range(repeats):
        result = renderer.render(scene, method, **params)
        times.append(result.total_ms)
    region = metrics.penumbra_region(truth)
    stray, out_of = metrics.stray_pixels(result.visibility, truth, result.object_id >= 0)
    return {
        "rmse": metrics.rmse(result.visibility, truth, region),
        "stray": 100.0 * stray / max(out_of, 1),
        "ms": statistics.median(times),
        "wedges": float(result.stats.get("wedges", float("nan"))),
        "in_wedge": float(result.stats.get("pixels_in_wedge", float("nan"))) / max(int(region.sum()), 1),
    }


def scenes_of(args: argparse.Namespace) -> dict[str, penumbra.Scene]:
    out = {name: penumbra.scenes.get(name, width=args.size, height=args.size) for name in penumbra.scenes.names()}
    if args.meshes.is_dir():
        out.update(penumbra.scenes.real_mesh_suite(str(args.meshes), width=args.size, height=args.size))
        for mesh in OPEN_MESHES:
            for radius in (0.3, 0.8):
                out[f"{mesh} close r={radius}"] = penumbra.scenes.from_mesh(str(args.meshes / mesh), width=args.size, height=args.size, light_radius=radius)
    else:
        print(f"(the shared meshes are not at {args.meshes}: built-in scenes only)\n")
    return out


def accuracy(renderer: penumbra.Renderer, scenes: dict[str, penumbra.Scene], args: argparse.Namespace) -> None:
    print("| scene | method | settings | penumbra RMSE | stray % | time / hard | wedges | pixels in a wedge / true penumbra |")
    print("|---|---|---|---|---|---|---|---|")
    summary: dict[tuple[str, str], list[float]] = {}
    for name, scene in scenes.items():
        gt = pm.ground_truth(scene, spp=args.spp, noise_seed=1, kinds=("visibility",))
        hard_ms = None
        for method, params in CONFIGS:
            m = measure(renderer, scene, method, params, gt.visibility, args.repeats)
            hard_ms = m["ms"] if method == "hard" else hard_ms
            assert hard_ms is not None
            summary.setdefault((method, shown(method, params)), []).append(m["rmse"])
            extra = f"{int(m['wedges'])} | {m['in_wedge']:.2f}" if method == "wedges" else " | "
            print(f"| {name} | {method} | {shown(method, params)} | {m['rmse']:.4f} | {m['stray']:.2f} | {m['ms'] / hard_ms:.2f} | {extra} |", flush=True)
        assert gt.second is not None
        noise = metrics.rmse(gt.second.visibility, gt.visibility, metrics.penumbra_region(gt.visibility)) / np.sqrt(2)
        print(f"| {name} | *ground-truth noise* | | {noise:.4f} | | | | |")
    print("\nMean penumbra RMSE over all scenes above\n")
    print("| method | settings | mean penumbra RMSE |")
    print("|---|---|---|")
    for (method, settings), values in summary.items():
        print(f"| {method} | {settings} | {np.mean(values):.4f} |")


def long_edge_scene(radius: float) -> penumbra.Scene:
    # tests/test_pvm.py's: a bar 8 long at height 2, its top +z edge at z = 1.5.
    bar = box((0.0, 2.0, 0.0), (8.0, 0.2, 3.0), object_id=1, name="bar")
    light = penumbra.SphereLight((0.0, 6.0, 0.0), radius, intensity=60.0)
    camera = penumbra.Camera(eye=(0.0, 5.0, 5.5), target=(0.0, 0.0, 2.0), fov_y=30, width=160, height=160)
    return penumbra.Scene([ground_slab(), bar], light, camera)


def disk_cut(p: np.ndarray, h0: np.ndarray, h1: np.ndarray, light: np.ndarray, radius: float, occluder: np.ndarray) -> np.ndarray:
    n = np.cross(h1 - h0, p - h0)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    towards = np.sign(((occluder - h0) * n).sum(-1))
    u = np.clip(((light - h0) * n).sum(-1) * towards / radius, -1, 1)
    return (np.arccos(u) - u * np.sqrt(1 - u * u)) / np.pi


def single_edge(renderer: penumbra.Renderer) -> None:
    print("\nOne long edge: wedges' interpolation (Eq. 1-3) minus the exact disk cut, over the edge's penumbra on the ground (160x160, columns 70-89)\n")
    print("| radius | settings | pixels | max abs. difference | RMS difference | mean on the umbra side (k < 0.3) | mean on the lit side (k > 0.7) |")
    print("|---|---|---|---|---|---|---|")
    for radius in (0.3, 0.8, 1.5):
        scene = long_edge_scene(radius)
        for params in ({}, {"falloff": True}):
            result = renderer.render(scene, "wedges", **params)
            columns = slice(70, 90)
            v = result.visibility[:, columns]
            inside = (result.object_id[:, columns] == 0) & (result.position[:, columns, 2] > 0.0) & (v > 0.02) & (v < 0.98)
            p = result.position[:, columns][inside].astype(np.float64)
            k = disk_cut(p, np.array([-4.0, 2.1, 1.5]), np.array([4.0, 2.1, 1.5]), scene.light.center.astype(float), radius, np.array([0.0, 2.0, 0.0]))
            d = v[inside] - k
            print(f"| {radius} | {shown('wedges', params)} | {len(d)} | {np.abs(d).max():.4f} | {np.sqrt(np.mean(d**2)):.4f} | {d[k < 0.3].mean():+.4f} | {d[k > 0.7].mean():+.4f} |")
    # The shape alone: linear in the chord's offset against the segment's area.
    u = np.linspace(-1, 1, 20001)
    shape = np.abs((1 - u) / 2 - (np.arccos(u) - u * np.sqrt(1 - u * u)) / np.pi).max()
    print(f"\n(linear against the disk segment's S-curve in the chord's offset alone: {shape:.4f} at most)")


def prism(points: list[tuple[float, float]], y0: float, y1: float) -> penumbra.Mesh:
    pts = np.asarray(points, float)
    n = len(pts)
    v = np.vstack([np.c_[pts[:, 0], np.full(n, y0), pts[:, 1]], np.c_[pts[:, 0], np.full(n, y1), pts[:, 1]]])
    faces = [[0, i + 1, i] for i in range(1, n - 1)] + [[n, n + i, n + i + 1] for i in range(1, n - 1)]
    for i in range(n):
        j = (i + 1) % n
        faces += [[i, j, n + j], [i, n + j, n + i]]
    f = np.array(faces)
    if trimesh.Trimesh(v, f, process=False).volume < 0:
        f = f[:, ::-1]
    return penumbra.Mesh(v, f, object_id=1, name="prism")


def acute(renderer: penumbra.Renderer, args: argparse.Namespace) -> None:
    print("\nacute_wedges on a thin triangular prism (23-degree tip) 1.9 over the ground, light at height 5 (128x128): penumbra RMSE against Mitsuba\n")
    print("| radius | hard | pvm | wedges acute_wedges=0 | 3 | 6 | 12 | 6, falloff | extra wedges at 6 |")
    print("|---|---|---|---|---|---|---|---|---|")
    caster = prism([(-1.5, -0.6), (1.5, 0.0), (-1.5, 0.6)], 1.9, 2.0)
    for radius in (0.3, 0.6):
        light = penumbra.SphereLight((0.0, 5.0, 0.0), radius, intensity=40.0)
        camera = penumbra.Camera.look_at((0.0, 6.0, 3.0), (0.3, 0.0, 0.0), fov_y=45, width=128, height=128)
        scene = penumbra.Scene([ground_slab(half_size=4.0), caster], light, camera)
        gt = pm.ground_truth(scene, spp=args.spp, kinds=("visibility",)).visibility
        region = metrics.penumbra_region(gt)
        cells = []
        for method, params in [("hard", {}), ("pvm", {})] + [("wedges", {"acute_wedges": n}) for n in (0, 3, 6, 12)] + [("wedges", {"acute_wedges": 6, "falloff": True})]:
            cells.append(f"{metrics.rmse(renderer.render(scene, method, **params).visibility, gt, region):.4f}")
        extra = renderer.render(scene, "wedges", acute_wedges=6).stats["extra_wedges"]
        print(f"| {radius} | " + " | ".join(cells) + f" | {extra} |")


def repairs(renderer: penumbra.Renderer, scenes: dict[str, penumbra.Scene], args: argparse.Namespace) -> None:
    print("\nrepairs, cumulative: penumbra RMSE (stray %)\n")
    names = list(scenes)
    print("| repairs | " + " | ".join(names) + " |")
    print("|---|" + "---|" * len(names))
    for level in LEVELS:
        cells = []
        for n in names:
            truth = pm.ground_truth(scenes[n], spp=args.spp, kinds=("visibility",)).visibility
            result = renderer.render(scenes[n], "wedges", repairs=level)
            stray, out_of = metrics.stray_pixels(result.visibility, truth, result.object_id >= 0)
            cells.append(f"{metrics.rmse(result.visibility, truth, metrics.penumbra_region(truth)):.3f} ({100 * stray / max(out_of, 1):.2f})")
        print(f"| {level} | " + " | ".join(cells) + " |", flush=True)
    print("\nSilhouettes as wedges sees them (stats of one render each, repairs='all')\n")
    print("| scene | silhouette edges | hidden from the light centre | wedges | junction vertices | side lines outside the light cone | extra wedges at acute_wedges=6 |")
    print("|---|---|---|---|---|---|---|")
    for n in names:
        s = renderer.render(scenes[n], "wedges").stats
        extra = renderer.render(scenes[n], "wedges", acute_wedges=6).stats["extra_wedges"]
        print(f"| {n} | {s['silhouette_edges']} | {s['hidden_silhouette_edges']} | {s['wedges']} | {s['silhouette_junction_vertices']} | {s['side_line_fallbacks']} | {extra} |")


def pictures(renderer: penumbra.Renderer, folder: Path, args: argparse.Namespace) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    overlap = penumbra.scenes.get("overlapping_casters", width=128, height=128)
    large = penumbra.scenes.get("sphere_on_plane", width=128, height=128, light_radius=1.5)
    rows = [("overlapping casters, r = 0.5", overlap), ("one silhouette for a large light: sphere, r = 1.5", large)]
    fig, axes = plt.subplots(2, 5, figsize=(15, 6.4))
    for row, (title, scene) in enumerate(rows):
        truth = pm.ground_truth(scene, spp=args.spp, kinds=("visibility",)).visibility
        tiles = [
            ("Mitsuba", truth),
            ("wedges", renderer.render(scene, "wedges").visibility),
            ("wedges hard_term=lit_side", renderer.render(scene, "wedges", hard_term="lit_side").visibility),
            ("pvm", renderer.render(scene, "pvm").visibility),
        ]
        for col, (name, image) in enumerate(tiles):
            axes[row, col].imshow(image, cmap="gray", vmin=0, vmax=1)
            axes[row, col].set_title(name if col else f"{title}\n{name}", fontsize=9)
        axes[row, 4].imshow(tiles[1][1] - truth, cmap="RdBu_r", vmin=-0.5, vmax=0.5)
        axes[row, 4].set_title("wedges - Mitsuba (red: too lit)", fontsize=9)
        for ax in axes[row]:
            ax.axis("off")
    fig.tight_layout()
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "wedges_limits.png"
    fig.savefig(path, dpi=72)
    print(f"\nwrote {path}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=96)
    parser.add_argument("--spp", type=int, default=256)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--meshes", type=Path, default=MESHES)
    parser.add_argument("--images", type=Path, help="folder for wedges_limits.png")
    args = parser.parse_args()
    # No pass cache: the repeats are timed, so every pass must run each time.
    renderer = penumbra.Renderer(pass_cache=False)
    print(f"adapter {renderer.adapter_info['name']}; {args.size}x{args.size}; Mitsuba {pm.variant()} visibility at {args.spp} samples; median of {args.repeats} renders")
    print(f"command: python {' '.join(sys.argv)}\n")
    scenes = scenes_of(args)
    accuracy(renderer, scenes, args)
    single_edge(renderer)
    acute(renderer, args)
    repairs(renderer, scenes, args)
    if args.images is not None:
        pictures(renderer, args.images, args)


if __name__ == "__main__":
    main()

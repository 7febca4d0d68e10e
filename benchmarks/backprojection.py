"""`backprojection` (Guennebaud et al. 2007) against Mitsuba visibility ground
truth beside `hard`, `pcss`, `pvmf` (the settings docs/real_meshes.md
recommends) and `reference` with 1024 light samples: the tables of
docs/methods/backprojection.md (issue 20).

Scenes: every built-in scene; with the meshes folder, the real-mesh suite
(`penumbra.scenes.real_mesh_suite`: cube, spot, teapot close at two light
radii and on a wide floor) and the open and non-manifold meshes
(bun_zipper.ply with holes, bun_zipper_res4.ply, CornellBox-Original.obj)
seen close at radius 0.3.

Columns (as benchmarks/real_meshes.py):
- penumbra RMSE: visibility RMSE over the pixels whose ground-truth
  visibility is strictly inside (0.02, 0.98) (`penumbra.metrics`);
- stray %: pixels fully lit in truth that the method darkens below 0.5, or
  in the umbra in truth that it lights above 0.5, per cent of all such pixels;
- time / hard: median wall clock of the render call over `--repeats` renders
  after a warm-up, every pass recomputed (`Renderer(pass_cache=False)`),
  over `hard`'s on the same scene in this run.

`backprojection` runs four ways: the faithful defaults (both adaptive
strategies on), light-space multi-resolution (5.1) off, screen-space
multi-resolution (5.2) off, both off, and t_k = 16 (5.1 on, levels one
finer than the paper's t_k = 8). Then the issue's targets per
configuration (worst scene), a light-radius sweep on cube_on_plane, and
one straight edge against the exact disk coverage as it moves across a
coarse texel.

    python benchmarks/backprojection.py [--size 128] [--spp 1024] [--repeats 3] [--meshes ../shared/meshes] [--skip builtin real open sweep edge] [--methods hard pcss ...]
"""

from __future__ import annotations

import argparse
import statistics
from pathlib import Path
from typing import Any

import numpy as np

import penumbra
from penumbra.comparison import RECOMMENDED
from penumbra import metrics
from penumbra import mitsuba as pm

MESHES = Path(__file__).resolve().parents[1] / ".." / "shared" / "meshes"
OPEN_MESHES = ("bun_zipper.ply", "bun_zipper_res4.ply", "CornellBox-Original.obj")
PVMF_RECOMMENDED: dict[str, Any] = RECOMMENDED["pvmf"]

BP_CONFIGS: list[tuple[str, dict[str, Any]]] = [
    ("defaults", {}),
    ("5.1 off", {"light_adaptive": False}),
    ("5.2 off", {"screen_adaptive": False}),
    ("both off", {"light_adaptive": False, "screen_adaptive": False}),
    ("t_k=16", {"t_k": 16.0}),
]
CONFIGS: list[tuple[str, str, dict[str, Any]]] = [
    ("hard", "defaults", {}),
    ("pcss", "defaults", {}),
    ("pvmf", "recommended", PVMF_RECOMMENDED),
    ("reference", "n_samples=1024", {"n_samples": 1024}),
    *[("backprojection", label, params) for label, params in BP_CONFIGS],
]


def measure(renderer: penumbra.Renderer, scene: penumbra.Scene, method: str, params: dict[str, Any], truth: np.ndarray, repeats: int) -> dict[str, Any]:
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
        "penumbra": int(region.sum()),
        "stats": result.stats,
    }


def table(renderer: penumbra.Renderer, scenes: dict[str, penumbra.Scene], args: argparse.Namespace) -> dict[str, dict[tuple[str, str], dict[str, Any]]]:
    print("| scene | true penumbra px | method | settings | penumbra RMSE | stray % | time / hard | computed / penumbra px |")
    print("|---|---|---|---|---|---|---|---|")
    out: dict[str, dict[tuple[str, str], dict[str, Any]]] = {}
    for name, scene in scenes.items():
        gt = pm.ground_truth(scene, spp=args.spp, noise_seed=1, kinds=("visibility",))
        rows: dict[tuple[str, str], dict[str, Any]] = {}
        hard_ms = None
        for method, label, params in CONFIGS:
            if method not in args.methods:
                continue
            try:
                m = measure(renderer, scene, method, params, gt.visibility, 1 if method == "reference" else args.repeats)
            except penumbra.PenumbraError as e:
                print(f"| {name} | | {method} | {label} | {type(e).__name__}: {e} | | | |")
                continue
            if method == "hard":
                hard_ms = m["ms"]
            rows[(method, label)] = m
            ratio = f"{m['ms'] / hard_ms:.2f}" if hard_ms else ""
            s = m["stats"]
            computed = f"{s['penumbra_computed']} / {s['penumbra_pixels']}" if method == "backprojection" else ""
            print(f"| {name} | {m['penumbra']} | {method} | {label} | {m['rmse']:.4f} | {m['stray']:.3f} | {ratio} | {computed} |", flush=True)
            m["ratio"] = m["ms"] / hard_ms if hard_ms else float("nan")
        assert gt.second is not None
        noise = metrics.rmse(gt.second.visibility, gt.visibility, metrics.penumbra_region(gt.visibility)) / np.sqrt(2)
        print(f"| {name} | | *ground-truth noise* | | {noise:.4f} | | | |")
        out[name] = rows
    return out


def targets(results: dict[str, dict[tuple[str, str], dict[str, Any]]]) -> None:
    print("\nIssue 20's goal: penumbra RMSE <= 0.5 x pcss's at <= 2.5 x hard's time, every scene (worst scene; scenes meeting it)\n")
    print("| settings | worst RMSE / pcss's | worst time / hard | mean RMSE / pcss's | scenes meeting both |")
    print("|---|---|---|---|---|")
    for label, _ in BP_CONFIGS:
        rows = [(r[("backprojection", label)], r[("pcss", "defaults")]) for r in results.values() if ("backprojection", label) in r and ("pcss", "defaults") in r]
        if not rows:
            continue
        rel = [b["rmse"] / max(p["rmse"], 1e-9) for b, p in rows]
        ratio = [b["ratio"] for b, _ in rows]
        ok = sum(1 for r, t in zip(rel, ratio) if r <= 0.5 and t <= 2.5)
        print(f"| {label} | {max(rel):.2f} | {max(ratio):.2f} | {np.mean(rel):.2f} | {ok} of {len(rows)} |")


def sweep(renderer: penumbra.Renderer, args: argparse.Namespace) -> None:
    print("\nLight-radius sweep, cube_on_plane: penumbra RMSE and time / hard per setting\n")
    labels = ["pcss", *[f"backprojection {label}" for label, _ in BP_CONFIGS]]
    print("| radius | true penumbra px | " + " | ".join(labels) + " | levels used (defaults) |")
    print("|---|---|" + "---|" * (len(labels) + 1))
    for radius in (0.05, 0.1, 0.2, 0.4, 0.8):
        scene = penumbra.scenes.get("cube_on_plane", width=args.size, height=args.size, light_radius=radius)
        truth = pm.ground_truth(scene, spp=args.spp, kinds=("visibility",)).visibility
        hard = measure(renderer, scene, "hard", {}, truth, args.repeats)
        cells = []
        levels = ""
        for method, params in [("pcss", {}), *[("backprojection", p) for _, p in BP_CONFIGS]]:
            m = measure(renderer, scene, method, params, truth, args.repeats)
            cells.append(f"{m['rmse']:.4f} ({m['ms'] / hard['ms']:.2f})")
            if method == "backprojection" and not params:
                s = m["stats"]
                levels = ", ".join(f"{l}: {s[f'level_{l}_pixels']}" for l in range(8) if s[f"level_{l}_pixels"])
        print(f"| {radius} | {hard['penumbra']} | " + " | ".join(cells) + f" | {levels} |", flush=True)


def edge(renderer: penumbra.Renderer) -> None:
    """The single straight edge of tests/test_backprojection.py against the
    exact disk coverage, the edge moved across a level-2 texel in 8 steps."""
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from test_backprojection import edge_scene, exact_edge_visibility

    print("\nOne straight edge against the exact disk coverage (96x96): mean error and RMSE over the penumbra as the edge moves\n")
    print("| settings | levels | mean error per offset | mean of means | RMSE per offset |")
    print("|---|---|---|---|---|")
    for label, params in (("5.1 off", {"light_adaptive": False}), ("defaults", {}), ("t_k=4", {"t_k": 4.0})):
        means, rmses, levels = [], [], set()
        for x in np.linspace(0.0, 0.032, 9)[:-1]:
            scene = edge_scene(0.3, edge_x=float(x))
            exact = exact_edge_visibility(scene, float(x))
            result = renderer.render(scene, "backprojection", **params)
            region = (result.object_id == 0) & (exact > 0.02) & (exact < 0.98)
            err = result.visibility[region] - exact[region]
            means.append(float(err.mean()))
            rmses.append(float(np.sqrt(np.mean(err**2))))
            levels |= {level for level in range(8) if result.stats[f"level_{level}_pixels"]}
        fmt = lambda xs: " ".join(f"{x:+.3f}" for x in xs)  # noqa: E731
        print(f"| {label} | {sorted(levels)} | {fmt(means)} | {np.mean(means):+.4f} | {' '.join(f'{x:.3f}' for x in rmses)} |", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=128)
    parser.add_argument("--spp", type=int, default=1024)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--meshes", type=Path, default=MESHES)
    parser.add_argument("--methods", nargs="*", default=[m for m, _, _ in CONFIGS], help="methods of the table to run (hard always: the time baseline)")
    parser.add_argument("--skip", nargs="*", default=[], choices=["builtin", "real", "open", "sweep", "edge"], help="parts to leave out")
    args = parser.parse_args()
    args.methods = ["hard", *args.methods]
    renderer = penumbra.Renderer(pass_cache=False)
    print(f"adapter {renderer.adapter_info['name']}; {args.size}x{args.size}; ground truth Mitsuba {pm.variant()} visibility at {args.spp} samples, noise from a second seed; median of {args.repeats} renders\n")
    scenes: dict[str, penumbra.Scene] = {}
    if "builtin" not in args.skip:
        scenes.update({n: penumbra.scenes.get(n, width=args.size, height=args.size) for n in penumbra.scenes.names()})
    if args.meshes.is_dir():
        if "real" not in args.skip:
            scenes.update(penumbra.scenes.real_mesh_suite(str(args.meshes), width=args.size, height=args.size))
        if "open" not in args.skip:
            for mesh in OPEN_MESHES:
                scenes[f"{mesh} close r=0.3"] = penumbra.scenes.from_mesh(str(args.meshes / mesh), width=args.size, height=args.size, light_radius=0.3, setup="close")
    else:
        print(f"(no meshes folder at {args.meshes}: built-in scenes only)\n")
    if scenes:
        targets(table(renderer, scenes, args))
    if "sweep" not in args.skip:
        sweep(renderer, args)
    if "edge" not in args.skip:
        edge(renderer)


if __name__ == "__main__":
    main()

"""Straight edges against their exact coverage: the analytic checks of
docs/methods/wedges.md and docs/methods/backprojection.md (their tables
against Mitsuba: benchmarks/wedges.toml, benchmarks/backprojection.toml; the
acute caster: benchmarks/acute_wedges.toml).

    python benchmarks/exact_edges.py [--parts wedges backprojection]

- wedges: one long box edge over a plane, wedges' Eq. 1-3 interpolation
  against the exact fraction of the disk the plane through the edge and the
  pixel cuts (pvm's disk cut, Cournia Eq. 4.1), over the edge's penumbra;
- backprojection: tests/test_backprojection.py's single edge moved across a
  level-2 texel in 8 steps, against the exact disk coverage.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import penumbra
from penumbra.grid import label
from penumbra.scenes import box, ground_slab


def disk_cut(p: np.ndarray, h0: np.ndarray, h1: np.ndarray, light: np.ndarray, radius: float, occluder: np.ndarray) -> np.ndarray:
    """The fraction of the light's disk on the far side of the plane through the edge h0-h1 and each point p."""
    n = np.cross(h1 - h0, p - h0)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    u = np.clip(((light - h0) * n).sum(-1) * np.sign(((occluder - h0) * n).sum(-1)) / radius, -1, 1)
    return (np.arccos(u) - u * np.sqrt(1 - u * u)) / np.pi


def long_edge(renderer: penumbra.Renderer) -> None:
    """tests/test_pvm.py's bar 8 long at height 2, its top +z edge at z = 1.5."""
    print("| radius | settings | pixels | max abs. difference | RMS difference | mean on the umbra side (k < 0.3) | mean on the lit side (k > 0.7) |\n|---|---|---|---|---|---|---|")
    for radius in (0.3, 0.8, 1.5):
        camera = penumbra.Camera(eye=(0.0, 5.0, 5.5), target=(0.0, 0.0, 2.0), fov_y=30, width=160, height=160)
        scene = penumbra.Scene([ground_slab(), box((0.0, 2.0, 0.0), (8.0, 0.2, 3.0), object_id=1, name="bar")],
                               penumbra.SphereLight((0.0, 6.0, 0.0), radius, intensity=60.0), camera)
        for params in ({}, {"falloff": True}):
            result = renderer.render(scene, "wedges", **params)
            v, pos = result.visibility[:, 70:90], result.position[:, 70:90]
            inside = (result.object_id[:, 70:90] == 0) & (pos[..., 2] > 0.0) & (v > 0.02) & (v < 0.98)
            k = disk_cut(pos[inside].astype(np.float64), np.array([-4.0, 2.1, 1.5]), np.array([4.0, 2.1, 1.5]),
                         scene.light.center.astype(float), radius, np.array([0.0, 2.0, 0.0]))
            d = v[inside] - k
            print(f"| {radius} | {label(params)} | {len(d)} | {np.abs(d).max():.4f} | {np.sqrt(np.mean(d**2)):.4f} | {d[k < 0.3].mean():+.4f} | {d[k > 0.7].mean():+.4f} |")
    u = np.linspace(-1, 1, 20001)
    print(f"\n(linear against the disk segment's S-curve in the chord's offset alone: {np.abs((1 - u) / 2 - (np.arccos(u) - u * np.sqrt(1 - u * u)) / np.pi).max():.4f} at most)")


def backprojection_edge(renderer: penumbra.Renderer) -> None:
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from test_backprojection import edge_scene, exact_edge_visibility

    print("\n| settings | levels | mean error per offset | mean of means | RMSE per offset |\n|---|---|---|---|---|")
    settings = (
        ("5.1 off", {"light_adaptive": False}),
        ("defaults", {}),
        ("coarse_contour=centres (5.1's)", {"coarse_contour": "centres"}),
        ("t_k=4", {"t_k": 4.0}),
        ("t_k=4, centres", {"t_k": 4.0, "coarse_contour": "centres"}),
    )
    for name, params in settings:
        means, rmses, levels = [], [], set()
        for x in np.linspace(0.0, 0.032, 9)[:-1]:
            scene = edge_scene(0.3, edge_x=float(x))
            exact = exact_edge_visibility(scene, float(x))
            result = renderer.render(scene, "backprojection", **params)
            err = (result.visibility - exact)[(result.object_id == 0) & (exact > 0.02) & (exact < 0.98)]
            means.append(float(err.mean()))
            rmses.append(float(np.sqrt(np.mean(err**2))))
            levels |= {level for level in range(8) if result.stats[f"level_{level}_pixels"]}
        print(f"| {name} | {sorted(levels)} | {' '.join(f'{m:+.3f}' for m in means)} | {np.mean(means):+.4f} | {' '.join(f'{r:.3f}' for r in rmses)} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--parts", nargs="+", default=["wedges", "backprojection"], choices=["wedges", "backprojection"])
    args = parser.parse_args()
    renderer = penumbra.Renderer()
    for part in args.parts:
        {"wedges": long_edge, "backprojection": backprojection_edge}[part](renderer)


if __name__ == "__main__":
    main()

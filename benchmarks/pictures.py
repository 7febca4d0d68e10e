"""The pictures of the docs beside Mitsuba ground truth (their numbers come
from the benchmark configs):

- real_meshes_spot.png, real_meshes_teapot.png (docs/real_meshes.md):
  visibility of the truth, pvm with repairs="none" (the paper's construction
  as written), pvm and pvmf (its defaults), side by side,
  spot and the teapot seen close at radius 0.3, 160x160;
- wedges_limits.png (docs/methods/wedges.md): the paper's section 8
  limitations, overlapping wedges of two casters summed and one silhouette
  for a large light;
- pvm_overlap.png, pvm_discontinuity.png, pvm_single_silhouette.png
  (docs/methods/pvm.md, Cournia 4.3): penumbra.compare's figure of pvm.

    python benchmarks/pictures.py [--out docs/images] [--only real_meshes wedges pvm]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import penumbra
from penumbra import mitsuba as pm
from penumbra.comparison import compare


def real_meshes(renderer: penumbra.Renderer, out: Path) -> None:
    for mesh in ("spot.obj", "teapot-mcguire-closed.obj"):
        scene = penumbra.scenes.get(f"mesh:{mesh}", width=160, height=160, light_radius=0.3)
        tiles = [pm.ground_truth(scene, spp=1024, kinds=("visibility",)).visibility]
        tiles += [renderer.render(scene, m, **p).visibility for m, p in (("pvm", {"repairs": "none"}), ("pvm", {}), ("pvmf", {}))]
        gap = np.full((tiles[0].shape[0], 4), 0.5, dtype=np.float32)
        path = out / f"real_meshes_{mesh.split('.')[0].split('-')[0]}.png"
        penumbra.write_image(path, np.concatenate([t for tile in tiles for t in (tile, gap)][:-1], axis=1))
        print(f"wrote {path}: truth | pvm repairs=none | pvm | pvmf")


def wedges(renderer: penumbra.Renderer, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [("overlapping casters, r = 0.5", penumbra.scenes.get("overlapping_casters", width=128, height=128)),
            ("one silhouette for a large light: sphere, r = 1.5", penumbra.scenes.get("sphere_on_plane", width=128, height=128, light_radius=1.5))]
    fig, axes = plt.subplots(2, 5, figsize=(15, 6.4))
    for row, (title, scene) in enumerate(rows):
        truth = pm.ground_truth(scene, spp=256, kinds=("visibility",)).visibility
        tiles = [("Mitsuba", truth)] + [(f"{m} {' '.join(f'{k}={v}' for k, v in p.items())}".strip(), renderer.render(scene, m, **p).visibility)
                                        for m, p in (("wedges", {}), ("wedges", {"hard_term": "lit_side"}), ("pvm", {}))]
        for col, (name, image) in enumerate(tiles):
            axes[row, col].imshow(image, cmap="gray", vmin=0, vmax=1)
            axes[row, col].set_title(name if col else f"{title}\n{name}", fontsize=9)
        axes[row, 4].imshow(tiles[1][1] - truth, cmap="RdBu_r", vmin=-0.5, vmax=0.5)
        axes[row, 4].set_title("wedges - Mitsuba (red: too lit)", fontsize=9)
        for ax in axes[row]:
            ax.axis("off")
    fig.tight_layout()
    fig.savefig(out / "wedges_limits.png", dpi=72)
    print(f"wrote {out / 'wedges_limits.png'}")


def pvm(renderer: penumbra.Renderer, out: Path) -> None:
    cases = {"pvm_overlap.png": ("overlapping_casters", None), "pvm_discontinuity.png": ("cube_on_plane", None), "pvm_single_silhouette.png": ("sphere_on_plane", 2.0)}
    for name, (scene_name, radius) in cases.items():
        c = compare(penumbra.scenes.get(scene_name, width=320, height=320, light_radius=radius), "pvm", renderer=renderer, spp=1024, out=out / name)
        print(f"{out / name}: penumbra RMSE {c.metrics['visibility_rmse_penumbra']:.4f}, max error {c.metrics['visibility_max_error']:.3f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=Path("docs/images"))
    parser.add_argument("--only", nargs="+", default=["real_meshes", "wedges", "pvm"], choices=["real_meshes", "wedges", "pvm"])
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    renderer = penumbra.Renderer()
    for part in args.only:
        {"real_meshes": real_meshes, "wedges": wedges, "pvm": pvm}[part](renderer, args.out)


if __name__ == "__main__":
    main()

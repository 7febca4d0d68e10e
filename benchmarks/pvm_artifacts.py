"""Pictures of PVM's known artifacts (Cournia 4.3) next to Mitsuba ground truth.

- overlap: casters overlapping in light space overwrite each other's edges
  in the penumbra volume map (`overlapping_casters`);
- discontinuity: visibility jumps where the volumes of neighbouring
  silhouette edges meet (`cube_on_plane`, at the shadow's corners);
- single silhouette: the silhouette is taken from the light's centre only,
  wrong for a light large against the occluder (`sphere_on_plane`, radius 2).

    python benchmarks/pvm_artifacts.py [--out docs/images] [--size 320]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import penumbra
from penumbra.comparison import compare


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="docs/images")
    parser.add_argument("--size", type=int, default=320)
    parser.add_argument("--spp", type=int, default=1024)
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    renderer = penumbra.Renderer()
    cases = {
        "pvm_overlap.png": penumbra.scenes.get("overlapping_casters", width=args.size, height=args.size),
        "pvm_discontinuity.png": penumbra.scenes.get("cube_on_plane", width=args.size, height=args.size),
        "pvm_single_silhouette.png": penumbra.scenes.get("sphere_on_plane", width=args.size, height=args.size, light_radius=2.0),
    }
    for name, scene in cases.items():
        c = compare(scene, "pvm", renderer=renderer, spp=args.spp, out=out / name)
        print(f"{out / name}: penumbra RMSE {c.metrics['visibility_rmse_penumbra']:.4f}, max error {c.metrics['visibility_max_error']:.3f}")


if __name__ == "__main__":
    main()

"""Contact hardening on `resting_box`: the width of the 0.1-0.9 visibility
transition across the shadows of the box's two vertical silhouette edges, at
distances from the contact (world units; `penumbra.transition`), seen from
straight above. Prints one row per method.

    python benchmarks/contact_hardening.py [--size 160]
"""

from __future__ import annotations

import argparse
from typing import Any

import penumbra
from penumbra.transition import standing_edges, transition_width

DISTANCES = [0.15, 0.35, 0.55, 0.75]
CONFIGS: list[tuple[str, dict[str, Any]]] = [
    ("hard", {}),
    ("pcf", {}),
    ("pcss", {}),
    ("pcss", {"sampling": "poisson"}),
    ("pvm", {}),
    ("pvm", {"falloff": False}),
    ("pvmf", {}),
    # The settings docs/real_meshes.md recommends, with and without repair "distance".
    ("pvmf", {"kernel": "disk", "n_blur": 0, "offsets": "radius", "umbra": "skip", "s_e": 0.02}),
    ("pvmf", {"kernel": "disk", "n_blur": 0, "offsets": "radius", "umbra": "skip", "s_e": 0.02, "repairs": "hidden+horizon"}),
    ("reference", {"n_samples": 1024}),
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=160)
    args = parser.parse_args()
    renderer = penumbra.Renderer()
    scene = penumbra.scenes.get("resting_box")
    camera = penumbra.Camera(eye=(-0.8, 9.0, -0.8), target=(-0.8, 0.0, -0.8), up=(0, 0, -1), fov_y=20, width=args.size, height=args.size)
    foot, corners = standing_edges(scene, 1)
    print(f"resting_box from above, {args.size}x{args.size}; width of the 0.1-0.9 transition (world units) at distance t from the contact, edge 1 / edge 2\n")
    print("| method | params | " + " | ".join(f"t = {t}" for t in DISTANCES) + " |")
    print("|---|---|" + "---|" * len(DISTANCES))
    for method, params in CONFIGS:
        result = renderer.render(scene, method, camera=camera, **params)
        widths = [transition_width(result.visibility, result.position, result.object_id == 0, foot, c, DISTANCES) for c in corners]
        shown = ", ".join(f"{k}={v}" for k, v in params.items()) or "defaults"
        cells = " | ".join(f"{a:.2f} / {b:.2f}" for a, b in zip(*widths))
        print(f"| {method} | {shown} | {cells} |")


if __name__ == "__main__":
    main()

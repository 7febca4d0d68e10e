"""Rooms lit from inside (issue 31): every method against the truth and
under a rotation of the whole scene, over `penumbra.rooms.room_suite`.

    python benchmarks/rooms.py                       # 64x64, every method, the table
    python benchmarks/rooms.py --methods pcss pcf --scenes "corridor middle"
    python benchmarks/rooms.py --size 32 --methods pcss --param blocker_test=cone

Prints, per method, the worst and the mean over the scenes of the fraction
of pixels off the truth (`reference` at 1024 samples) by more than 0.1, and
of the fraction moved by more than 0.1 by the rotation (30 degrees about x,
20 about y), then every scene's row.
"""

from __future__ import annotations

import argparse

import numpy as np

import penumbra
from penumbra import rooms
from penumbra.cli import _param

METHODS = ["pcf", "pcss", "pvm", "pvmf", "wedges", "backprojection", "adaptive", "reference"]
# `reference` at low samples: the cheap way to the truth, beside the soft methods.
PARAMS = {"reference": {"n_samples": 64}}


def table(rows: list[rooms.RoomRow]) -> str:
    lines = [
        "| method | off the truth, worst | mean | moved by the rotation, worst | mean | truth moved, worst | scenes refused |",
        "|---|---|---|---|---|---|---|",
    ]
    for method in dict.fromkeys(r.method for r in rows):
        mine = [r for r in rows if r.method == method]
        done = [r for r in mine if r.off is not None]
        off = [max(r.off, r.off_rotated) for r in done]  # type: ignore[type-var]
        moved = [r.moved for r in done]
        if not done:
            lines.append(f"| `{method}` | | | | | | {len(mine)} |")
            continue
        lines.append(
            f"| `{method}` | {max(off):.1%} | {np.mean(off):.1%} | {max(moved):.1%} | {np.mean(moved):.1%} | "  # type: ignore[type-var,arg-type]
            f"{max(r.truth_moved for r in done):.1%} | {len(mine) - len(done)} |"
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=64)
    parser.add_argument("--methods", nargs="*", default=METHODS)
    parser.add_argument("--scenes", nargs="*", help="scene names of the suite (all by default)")
    parser.add_argument("--truth-samples", type=int, default=rooms.TRUTH_SAMPLES)
    parser.add_argument("--param", action="append", type=_param, default=[], metavar="KEY=VALUE", help="a parameter of every method given (repeatable)")
    args = parser.parse_args()
    params = {m: {**PARAMS.get(m, {}), **dict(args.param)} for m in args.methods}
    # The Cornell box's scenes come from the shared meshes (penumbra.scenes.meshes_folder), where present.
    meshes = penumbra.scenes.meshes_folder()
    cornell = meshes / "CornellBox-Original.obj" if meshes is not None else None
    suite = rooms.room_suite(args.size, str(cornell) if cornell is not None and cornell.exists() else None)
    if args.scenes:
        suite = {k: v for k, v in suite.items() if k in args.scenes}
    rows = rooms.measure(penumbra.Renderer(), suite, args.methods, params=params, truth_samples=args.truth_samples)
    print(f"## {len(suite)} room scenes at {args.size}x{args.size}, truth: reference at {args.truth_samples} samples\n")
    print(table(rows))
    print("\n| scene | method | off | off rotated | moved | truth moved |\n|---|---|---|---|---|---|")
    for r in rows:
        if r.off is None:
            print(f"| {r.scene} | {r.method} | refused: {r.refused[:60]} | | | {r.truth_moved:.1%} |")
        else:
            print(f"| {r.scene} | {r.method} | {r.off:.1%} | {r.off_rotated:.1%} | {r.moved:.1%} | {r.truth_moved:.1%} |")


if __name__ == "__main__":
    main()

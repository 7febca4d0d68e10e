"""Hashes of every image of every method, for A/B checks of refactors.

Renders each implemented method on every built-in scene (and the closed real
meshes of ../shared/meshes when present) with every parameter set of
`benchmarks/bench.toml`'s [methods] grids plus the method's defaults, with
intermediates, and prints (or writes) one SHA-256 per image:

    python benchmarks/image_hashes.py --out before.json      # on the old build
    python benchmarks/image_hashes.py --out after.json       # on the new build
    python benchmarks/image_hashes.py --compare before.json after.json

Hashes depend on the adapter and driver: compare runs on one machine.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

import penumbra
from penumbra.bench import expand

HERE = Path(__file__).resolve().parent
MESHES = HERE.parent.parent / "shared" / "meshes"


def _scenes(size: int) -> dict[str, penumbra.Scene]:
    out = {name: penumbra.scenes.get(name, width=size, height=size) for name in penumbra.scenes.names()}
    for name in ("spot.obj", "teapot-mcguire-closed.obj"):
        if (MESHES / name).exists():
            out[name] = penumbra.scenes.from_mesh(str(MESHES / name), width=size, height=size)
    return out


def hashes(size: int, methods: list[str] | None) -> dict[str, str]:
    grids = tomllib.loads((HERE / "bench.toml").read_text())["methods"]
    renderer = penumbra.Renderer(timing="cpu", pass_cache=False)
    out: dict[str, str] = {}
    for scene_name, scene in _scenes(size).items():
        for method in methods or penumbra.methods():
            settings: list[dict[str, Any]] = [{}] + expand(grids.get(method, []))
            if method == "reference":
                settings = [{"n_samples": 16}, {"n_samples": 16, "sampling": "disk"}]
            seen: set[str] = set()
            for params in settings:
                label = json.dumps(params, sort_keys=True)
                if label in seen:
                    continue
                seen.add(label)
                result = renderer.render(scene, method, intermediates=True, **params)
                for name, image in sorted(result.images.items()):
                    digest = hashlib.sha256(np.ascontiguousarray(image).tobytes()).hexdigest()[:16]
                    out[f"{scene_name} {method} {label} {name}"] = digest
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=64)
    parser.add_argument("--methods", nargs="*")
    parser.add_argument("--out")
    parser.add_argument("--compare", nargs=2, metavar=("BEFORE", "AFTER"))
    args = parser.parse_args()
    if args.compare:
        before, after = (json.loads(Path(p).read_text()) for p in args.compare)
        changed = sorted(k for k in before if k in after and before[k] != after[k])
        missing = sorted(set(before) - set(after))
        for k in changed:
            print(f"differs: {k}")
        for k in missing:
            print(f"missing: {k}")
        print(f"{len(before)} images before, {len(after)} after, {len(changed)} differ, {len(missing)} missing")
        return 1 if changed or missing else 0
    result = hashes(args.size, args.methods)
    text = json.dumps(result, indent=0, sort_keys=True)
    if args.out:
        Path(args.out).write_text(text)
        print(f"{len(result)} image hashes -> {args.out}", file=sys.stderr)
    else:
        print(text)
    return 0


if __name__ == "__main__":
    os.environ.setdefault("XDG_RUNTIME_DIR", "/tmp")
    sys.exit(main())

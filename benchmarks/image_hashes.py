"""Hashes of every image of every method, for A/B checks of refactors and drivers.

Renders each implemented method on every built-in scene (and the closed real
meshes spot and the teapot when the shared meshes are present) with every
parameter set of `benchmarks/bench.toml`'s [methods] grids plus the
method's defaults (`reference` at 16 samples, sphere and disk), with
intermediates, and prints (or writes) one SHA-256 per image:

    python benchmarks/image_hashes.py --out before.json      # on the old build
    python benchmarks/image_hashes.py --out after.json       # on the new build
    python benchmarks/image_hashes.py --compare before.json after.json

With `--images FILE.npz` the images themselves are kept too, and `--compare`
of two such files gives how far they differ, per kind of image (the largest
difference relative to the image's largest value, and the pixels that differ):
run under two Vulkan drivers (the loader's `VK_ICD_FILENAMES`, e.g. an older
Mesa's lavapipe unpacked with `dpkg -x`) for a driver A/B.

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


def _scenes(size: int) -> dict[str, penumbra.Scene]:
    out = {name: penumbra.scenes.get(name, width=size, height=size) for name in penumbra.scenes.names()}
    if penumbra.scenes.meshes_folder() is not None:
        out.update({name: penumbra.scenes.from_mesh(str(penumbra.scenes.meshes_folder() / name), width=size, height=size)
                    for name in ("spot.obj", "teapot-mcguire-closed.obj")})
    return out


def images(size: int, methods: list[str] | None) -> dict[str, np.ndarray]:
    """Every image, by "<scene> <method> <parameters> <image>"."""
    grids = tomllib.loads((Path(__file__).resolve().parent / "bench.toml").read_text())["methods"]
    renderer = penumbra.Renderer(timing="cpu", pass_cache=False)
    out: dict[str, np.ndarray] = {}
    for scene_name, scene in _scenes(size).items():
        for method in methods or penumbra.methods():
            settings: list[dict[str, Any]] = [{}] + expand(grids.get(method, []))
            if method == "reference":
                settings = [{"n_samples": 16}, {"n_samples": 16, "sampling": "disk"}]
            for label in dict.fromkeys(json.dumps(p, sort_keys=True) for p in settings):
                result = renderer.render(scene, method, intermediates=True, **json.loads(label))
                out.update({f"{scene_name} {method} {label} {name}": np.ascontiguousarray(image) for name, image in sorted(result.images.items())})
    return out


def compare_images(before: Path, after: Path) -> None:
    """The largest difference per kind of image, relative to the image's largest value, and the pixels that differ."""
    a, b = np.load(before), np.load(after)
    worst: dict[str, tuple[float, int]] = {}
    for key in a.files:
        d = np.abs(a[key].astype(np.float64) - b[key])
        kind = key.rsplit(" ", 1)[1]
        worst[kind] = max(worst.get(kind, (0.0, 0)), (float(d.max()) / max(float(np.abs(a[key]).max()), 1e-30), int((d > 0).sum())))
    for kind, (relative, pixels) in sorted(worst.items()):
        print(f"{kind}: largest difference {relative:.3g} of the image's largest value; at most {pixels} pixels differ")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=64)
    parser.add_argument("--methods", nargs="*")
    parser.add_argument("--out")
    parser.add_argument("--images", help="also keep the images in this .npz file")
    parser.add_argument("--compare", nargs=2, metavar=("BEFORE", "AFTER"), help="two --out files (hashes) or two --images files")
    args = parser.parse_args()
    if args.compare and args.compare[0].endswith(".npz"):
        compare_images(*map(Path, args.compare))
        return 0
    if args.compare:
        before, after = (json.loads(Path(p).read_text()) for p in args.compare)
        changed = sorted(k for k in before if k in after and before[k] != after[k])
        missing = sorted(set(before) - set(after))
        print("".join(f"differs: {k}\n" for k in changed) + "".join(f"missing: {k}\n" for k in missing), end="")
        print(f"{len(before)} images before, {len(after)} after, {len(changed)} differ, {len(missing)} missing")
        return 1 if changed or missing else 0
    found = images(args.size, args.methods)
    if args.images:
        np.savez(args.images, **found)
    hashes = {k: hashlib.sha256(v.tobytes()).hexdigest()[:16] for k, v in found.items()}
    text = json.dumps(hashes, indent=0, sort_keys=True)
    if args.out:
        Path(args.out).write_text(text)
        print(f"{len(hashes)} image hashes -> {args.out}", file=sys.stderr)
    else:
        print(text)
    return 0


if __name__ == "__main__":
    os.environ.setdefault("XDG_RUNTIME_DIR", "/tmp")
    sys.exit(main())

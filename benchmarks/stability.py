"""Measures what the tolerances of tests/test_properties.py bound (issue 8)
and where the scene's scale and place stop mattering (issue 22).

By default, for many more random scenes than CI runs (a seeded generator
drawing from the same ranges as the hypothesis strategy `scene_specs` and
`SCALES`), per method:

- scale and translation: the scene rendered as built and again scaled by
  10^e (e in -3..4) and moved by (3, -2, 5) * 10^e; the fraction of pixels
  whose visibility differs by more than 0.1, and the mean absolute difference
  (what MISMATCH_FRACTION and MEAN_DIFFERENCE bound);
- convergence: the method at radius 1e-5 caster sizes against `hard` at
  radius 0; the fraction of pixels differing by more than 0.5 (what
  CONVERGED_MISMATCH bounds), for every method but pcf.

Prints max, 99th percentile and median per method and over all methods.

With `--limits`: the numbers behind `MIN_EXTENT` and `MAX_COORDINATE` in
rust/penumbra-core/src/scene.rs, the property tests' scale range and
docs/stability.md's section on issue 22. For every method, the fixed box
scene of the property tests (FIXED_SPECS[0], 32x32, FAST parameters) at
scale 1 and again scaled by 10^e and moved by (3, -2, 5) x 10^e: the
fraction of pixels whose visibility differs by more than 0.1 and the mean
difference, or the typed error the scene gets; then `sphere_on_plane` moved
1e7 along every axis (not scaled): float32 resolves one unit there. With
Mitsuba installed, also how Mitsuba's own `obj` loader treats a mirroring
`to_world` (penumbra's export passes world-space vertices instead).

    XDG_RUNTIME_DIR=/tmp python3 benchmarks/stability.py [--scenes N] [--seed S]
    XDG_RUNTIME_DIR=/tmp python3 benchmarks/stability.py --limits
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import penumbra  # noqa: E402
from stress_scenes import FAST, METHODS, check_images  # noqa: E402
from test_properties import FIXED_SPECS, SCALE_FREE, SOFT_METHODS, SceneSpec, spec_from, translated_default_scene, visibility_difference  # noqa: E402

#: The scales of `--limits`: 10^e for each e.
EXPONENTS = [-24, -23, -22, -21, -19, -18, -7, 9, 10, 12, 16, 17]


def random_spec(rng: np.random.Generator) -> SceneSpec:
    """One draw from the ranges of test_properties.scene_specs, with ``rng``."""
    return spec_from(rng.uniform, lambda xs: rng.choice(xs).item(), lambda: rng.random() < 0.5, lambda a, b: int(rng.integers(a, b + 1)))


def render(renderer: penumbra.Renderer, scene: penumbra.Scene, method: str) -> np.ndarray | None:
    try:
        return renderer.render(scene, method, **FAST[method]).visibility
    except penumbra.SceneError as e:
        # The one refusal a valid random scene can have (test_properties.render).
        assert "surrounds the light" in str(e), e
        return None


def summary(name: str, values: list[float]) -> str:
    v = np.asarray(values)
    if v.size == 0:
        return f"  {name:10s} n=0"
    return f"  {name:10s} n={v.size:4d}  max={v.max():.4f}  p99={np.percentile(v, 99):.4f}  median={np.median(v):.4f}"


def scale_table(renderer: penumbra.Renderer) -> None:
    spec = FIXED_SPECS[0]
    print("| method | " + " | ".join(f"1e{e}" for e in EXPONENTS) + " |")
    print("|---|" + "---|" * len(EXPONENTS))
    for method in METHODS:
        params = {**FAST[method], **SCALE_FREE.get(method, {})}
        base = renderer.render(spec.build(), method, **params).visibility
        cells = []
        for e in EXPONENTS:
            s = 10.0**e
            try:
                moved = renderer.render(spec.build(scale=s, offset=(3 * s, -2 * s, 5 * s)), method, **params)
                check_images(moved)
                frac, mean = visibility_difference(base, moved.visibility)
                cells.append(f"{frac:.4f} / {mean:.4f}")
            except penumbra.PenumbraError as error:
                cells.append(type(error).__name__)
        print(f"| {method} | " + " | ".join(cells) + " |")


def translation_table(renderer: penumbra.Renderer) -> None:
    print("\n| method | sphere_on_plane moved by 1e7: pixels differing > 0.1 | mean difference |")
    print("|---|---|---|")
    for method in METHODS:
        base = renderer.render(translated_default_scene(0.0), method, **FAST[method]).visibility
        far = renderer.render(translated_default_scene(1e7), method, **FAST[method]).visibility
        frac, mean = visibility_difference(base, far)
        print(f"| {method} | {frac:.4f} | {mean:.4f} |")


def mitsuba_mirror() -> None:
    try:
        import mitsuba as mi
    except ImportError:
        print("\n(Mitsuba not installed: no mirror check)")
        return
    mi.set_variant("scalar_rgb")
    with tempfile.TemporaryDirectory() as folder:
        obj = Path(folder) / "quad.obj"
        obj.write_text("v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 1 3 2\nf 1 4 3\n")
        print("\nMitsuba's own loaders under a mirroring to_world (a quad facing +y, lit from above):")
        for shape in ("obj", "rectangle"):
            for sx in (1.0, -1.0):
                t = mi.ScalarTransform4f().scale([sx, 1.0, 1.0])
                if shape == "obj":
                    desc = {"type": "obj", "filename": str(obj), "to_world": t, "bsdf": {"type": "diffuse"}}
                else:
                    desc = {"type": "rectangle", "to_world": t.rotate([1, 0, 0], -90), "bsdf": {"type": "diffuse"}}
                scene = mi.load_dict({
                    "type": "scene", "integrator": {"type": "direct"},
                    "sensor": {"type": "perspective", "fov": 40,
                               "to_world": mi.ScalarTransform4f().look_at(origin=[0, 4, 0.01], target=[0, 0, 0], up=[0, 0, 1]),
                               "film": {"type": "hdrfilm", "width": 8, "height": 8}, "sampler": {"type": "independent", "sample_count": 4}},
                    "quad": desc, "light": {"type": "point", "position": [0, 3, 0], "intensity": {"type": "rgb", "value": 10}},
                })
                print(f"  {shape:9s} scale x {sx:+.0f}: mean radiance {float(np.array(mi.render(scene)).mean()):.4f}")


def random_scenes(count: int, seed: int) -> None:
    """The default study: ``count`` random scenes drawn with ``seed``."""
    rng = np.random.default_rng(seed)
    specs = [(random_spec(rng), int(rng.integers(-3, 5))) for _ in range(count)]
    renderer = penumbra.Renderer()
    fraction: dict[str, list[float]] = {m: [] for m in METHODS}
    mean: dict[str, list[float]] = {m: [] for m in METHODS}
    converged: dict[str, list[float]] = {m: [] for m in SOFT_METHODS}
    worst: dict[str, tuple[float, str]] = {}
    start = time.perf_counter()
    for spec, e in specs:
        s = 10.0**e
        for method in METHODS:
            a = render(renderer, spec.build(), method)
            b = render(renderer, spec.build(scale=s, offset=(3.0 * s, -2.0 * s, 5.0 * s)), method)
            if a is None or b is None:
                continue
            f, m = visibility_difference(a, b)
            fraction[method].append(f)
            mean[method].append(m)
            if f > worst.get(method, (-1.0, ""))[0]:
                worst[method] = (f, f"{spec} at 1e{e}")
        hard = render(renderer, replace(spec, radius=0.0).build(), "hard")
        for method in SOFT_METHODS:
            tiny = render(renderer, replace(spec, radius=1e-5 * spec.size).build(), method)
            if hard is None or tiny is None:
                continue
            converged[method].append(float((np.abs(tiny - hard) > 0.5).mean()))
    print(f"{count} random scenes, seed {seed}, {time.perf_counter() - start:.0f} s; 32x32 images, FAST parameters")
    print("scale+translation: fraction of pixels differing by > 0.1 (MISMATCH_FRACTION)")
    for method in METHODS:
        print(summary(method, fraction[method]))
    print(summary("all", sum(fraction.values(), [])))
    print("scale+translation: mean absolute difference (MEAN_DIFFERENCE)")
    for method in METHODS:
        print(summary(method, mean[method]))
    print(summary("all", sum(mean.values(), [])))
    print("radius 1e-5 vs hard: fraction of pixels differing by > 0.5 (CONVERGED_MISMATCH)")
    for method in SOFT_METHODS:
        print(summary(method, converged[method]))
    print(summary("all", sum(converged.values(), [])))
    print("largest scale+translation mismatch per method:")
    for method, (f, what) in worst.items():
        print(f"  {method}: {f:.4f} {what}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scenes", type=int, default=100, help="random scenes per method (default 100)")
    parser.add_argument("--seed", type=int, default=8)
    parser.add_argument("--limits", action="store_true", help="the scale and translation limits of issue 22 instead")
    args = parser.parse_args()
    if not args.limits:
        random_scenes(args.scenes, args.seed)
        return
    renderer = penumbra.Renderer()
    scale_table(renderer)
    translation_table(renderer)
    mitsuba_mirror()


if __name__ == "__main__":
    main()

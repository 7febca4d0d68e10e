"""Where the scene's scale and place stop mattering, and where they start
(issue 22): the numbers behind `MIN_EXTENT` and `MAX_COORDINATE` in
rust/penumbra-core/src/scene.rs, the property tests' scale range and the
stability report's section on issue 22.

For every method, the fixed box scene of `tests/test_properties.py`
(FIXED_SPECS[0], 32x32, FAST parameters) is rendered at scale 1 and again
scaled by 10^e and moved by (3, -2, 5) x 10^e; printed: the fraction of
pixels whose visibility differs by more than 0.1, and the mean difference,
or the typed error the scene gets. Then `sphere_on_plane` moved 1e7 along
every axis (not scaled): float32 resolves one unit there.

With Mitsuba installed, also how Mitsuba's own `obj` loader treats a mirroring
`to_world` (penumbra's export passes world-space vertices instead).

    XDG_RUNTIME_DIR=/tmp python3 benchmarks/scale_limits.py
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

import penumbra

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from stress_scenes import FAST, METHODS, check_images  # noqa: E402
from test_properties import FIXED_SPECS, SCALE_FREE, translated_default_scene, visibility_difference  # noqa: E402

EXPONENTS = [-24, -23, -22, -21, -19, -18, -7, 9, 10, 12, 16, 17]


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


def main() -> None:
    renderer = penumbra.Renderer()
    scale_table(renderer)
    translation_table(renderer)
    mitsuba_mirror()


if __name__ == "__main__":
    main()

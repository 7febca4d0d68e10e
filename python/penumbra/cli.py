"""The command line: ``penumbra render | compare | bench | scenes | methods | info``."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any, Sequence

from penumbra import scenes
from penumbra.errors import ParameterError, PenumbraError
from penumbra.render import Renderer, adapter_info, methods


def _param(text: str) -> tuple[str, Any]:
    """``key=value`` with value parsed as int, float, bool or string."""
    if "=" not in text:
        raise ParameterError(f"--param takes key=value, got {text!r}")
    key, raw = text.split("=", 1)
    value: Any = raw
    if raw.lower() in ("true", "false"):
        value = raw.lower() == "true"
    else:
        for cast in (int, float):
            try:
                value = cast(raw)
                break
            except ValueError:
                pass
    return key.strip(), value


def _scene(args: argparse.Namespace) -> scenes.Scene:
    if args.mesh:
        size = {k: v for k, v in (("width", args.width), ("height", args.height)) if v is not None}
        scene = scenes.from_mesh(args.mesh, **size)
    else:
        scene = scenes.get(args.scene, width=args.width, height=args.height)
    if args.light_radius is not None:
        scene = scene.with_light(scene.light.with_radius(args.light_radius))
    return scene


def _render(args: argparse.Namespace) -> int:
    scene = _scene(args)
    params = dict(_param(p) for p in args.param)
    renderer = Renderer()
    result = renderer.render(scene, args.method, **params)
    result.save(args.output, image=args.image)
    print(f"scene {scene.name}: method {result.method} {json.dumps(result.params)}")
    print(f"adapter: {renderer.adapter_info['name']} ({renderer.adapter_info['backend']})")
    passes = ", ".join(f"{k} {v:.2f}" for k, v in result.timings.items())
    print(f"timings ({result.timing_source}, ms): {passes}; total {result.total_ms:.1f}")
    print(f"stats: {json.dumps(result.stats)}")
    print(f"wrote {args.image} to {args.output}")
    return 0


def _compare(args: argparse.Namespace) -> int:
    from penumbra.comparison import compare
    from penumbra.metrics import summary

    scene = _scene(args)
    params = dict(_param(p) for p in args.param)
    c = compare(scene, args.method, spp=args.spp, cache_dir=args.cache_dir, out=args.output, truth=args.truth, **params)
    gt = c.ground_truth
    truth = "raytraced truth" if gt.variant == "raytraced" else f"mitsuba {gt.variant}"
    print(f"scene {scene.name}: method {c.result.method} {json.dumps(c.result.params)}")
    print(f"penumbra: {c.result.total_ms:.1f} ms ({c.result.timing_source}); "
          f"{truth}, {gt.spp} spp: " + ", ".join(f"{k} {v:.2f} s{' (cached)' if gt.cached[k] else ''}" for k, v in gt.seconds.items()))
    print(summary(c.metrics))
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"scene": scene.name, "method": c.result.method, "params": c.result.params, "metrics": c.metrics}, f, indent=2)
    print(f"wrote the comparison to {args.output}")
    return 0


def _scene_arguments(parser: argparse.ArgumentParser) -> None:
    source = parser.add_mutually_exclusive_group()
    source.add_argument("--scene", default=scenes.DEFAULT, help=f"built-in scene (default {scenes.DEFAULT}; see `penumbra scenes`)")
    source.add_argument("--mesh", help="a mesh file trimesh can read, placed on the ground plane")
    parser.add_argument("--method", default="hard", help="shadow method (default hard)")
    parser.add_argument("--width", type=int, help="image width in pixels")
    parser.add_argument("--height", type=int, help="image height in pixels")
    parser.add_argument("--light-radius", type=float, help="override the light's radius")
    parser.add_argument("--param", action="append", default=[], metavar="KEY=VALUE", help="method parameter, repeatable")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="penumbra", description="Headless soft-shadow renderer.")
    sub = parser.add_subparsers(dest="command", required=True)

    render = sub.add_parser("render", help="render a built-in scene or a mesh file")
    _scene_arguments(render)
    render.add_argument("--image", default="radiance", help="which image to write (radiance, visibility, depth, ...)")
    render.add_argument("-o", "--output", default="penumbra.png", help="output file: .png (sRGB), .exr or .npy (linear)")
    render.set_defaults(run=_render)

    comp = sub.add_parser("compare", help="render a method and ground truth (Mitsuba or raytraced), print the metrics, write a side-by-side PNG")
    _scene_arguments(comp)
    comp.add_argument("--spp", type=int, default=256, help="ground-truth samples per pixel (default 256)")
    comp.add_argument(
        "--truth", choices=["mitsuba", "raytraced"], default="mitsuba",
        help="the ground truth: Mitsuba (default) or the engine's raytraced method at --spp light samples (give it thousands)",
    )
    comp.add_argument("--cache-dir", help="ground-truth cache folder (default $PENUMBRA_CACHE_DIR or ~/.cache/penumbra)")
    comp.add_argument("--json", help="also write the metrics to this JSON file")
    comp.add_argument("-o", "--output", default="compare.png", help="the comparison picture (PNG)")
    comp.set_defaults(run=_compare)

    from penumbra import bench

    bench_parser = sub.add_parser(
        "bench", help="run time against error for every method, Mitsuba and reference as peers (see benchmarks/bench.toml)"
    )
    bench.build_parser(bench_parser).set_defaults(run=bench.run_from_args)

    sub.add_parser("scenes", help="list the built-in scenes").set_defaults(run=lambda a: print("\n".join(scenes.names())) or 0)
    listing = sub.add_parser("methods", help="list the implemented methods (with --params, their parameters)")
    listing.add_argument("--params", action="store_true", help="each method's paper and parameters")
    listing.add_argument("--markdown", action="store_true", help="the parameter tables of docs/parameters.md")
    listing.set_defaults(run=_methods)
    sub.add_parser("info", help="show the GPU adapter in use (and whether it has ray queries, for raytraced)").set_defaults(run=lambda a: print(json.dumps(adapter_info(), indent=2)) or 0)
    return parser


def _methods(args: argparse.Namespace) -> int:
    from penumbra.render import method_info

    if args.markdown:
        print(parameters_markdown(), end="")
        return 0
    for name in methods():
        if not args.params:
            print(name)
            continue
        info = method_info(name)
        print(f"{name}: {info.paper}")
        for p in info.params:
            print(f"    {p.name} = {p.default!r}: {p.range}; {p.doc}")
    return 0


def parameters_markdown() -> str:
    """The text of docs/parameters.md: every implemented method's parameters,
    from the declarations the core checks them against."""
    from penumbra.render import method_info, parameter_table

    parts = [
        "# Method parameters",
        "",
        "Generated from the core's method registry by `python -m penumbra methods --markdown`",
        "(`tests/test_readme.py` checks that this page is current). In Python,",
        "`penumbra.method_info(name)` returns the same declarations.",
    ]
    for name in methods():
        paper = method_info(name).paper
        parts += ["", f"## `{name}`", "", paper[0].upper() + paper[1:] + ".", "", parameter_table(name)]
    return "\n".join(parts) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return int(args.run(args))
    except PenumbraError as e:
        print(f"penumbra: error: {e}", file=sys.stderr)
        return 2
    except OSError as e:  # a file the command writes itself (e.g. --json)
        print(f"penumbra: error: {e.filename or ''}: {e.strerror or e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())

"""The command line: ``penumbra render | compare | bench | scenes | methods | info``."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any, Sequence

from penumbra import scenes
from penumbra.comparison import DEFAULT_BUDGET_S, DEFAULT_REPEATS
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


def _scene(args: argparse.Namespace, default_size: int | None = None) -> scenes.Scene:
    width = args.width if args.width is not None or args.height is not None else default_size
    height = args.height if args.width is not None or args.height is not None else default_size
    if args.mesh:
        scene = scenes.from_mesh(args.mesh)
        if scene.camera is not None and (width is not None or height is not None):
            scene = scene.with_camera(scene.camera.with_size(width or scene.camera.width, height or scene.camera.height))
    else:
        scene = scenes.get(args.scene, width=width, height=height)
    if args.light_radius is not None:
        scene = scene.with_light(scene.light.with_radius(args.light_radius))
    return scene


def _size(scene: scenes.Scene) -> str:
    return f"{scene.camera.width}x{scene.camera.height}" if scene.camera else ""


def _adapter(info: dict[str, Any]) -> str:
    return f"{info['name']} ({info['backend']}{', software' if info.get('is_software') else ''})"


def _render(args: argparse.Namespace) -> int:
    from penumbra.comparison import timed_render, timing_renderer

    from penumbra.render import image_extension

    image_extension(args.output)  # refused before the render, not after
    scene = _scene(args)
    params = dict(_param(p) for p in args.param)
    if args.repeats < 0:
        raise ParameterError(f"--repeats must be at least 0, got {args.repeats}")
    renderer = timing_renderer()
    if args.repeats:
        result, timing = timed_render(renderer, scene, args.method, repeats=args.repeats, **params)
        took = f"warm time {timing.warm_ms:.1f} ms ({timing.describe()}); first render {timing.cold_ms:.0f} ms"
    else:
        result = renderer.render(scene, args.method, **params)
        took = f"time {result.total_ms:.1f} ms (wall clock of one render call, the first: pipelines included)"
    result.save(args.output, image=args.image)
    print(f"scene {scene.name}, {_size(scene)}: method {result.method}")
    print(f"parameters: {json.dumps(result.params)}")
    print(took)
    passes = ", ".join(f"{k} {v:.2f}" for k, v in result.timings.items())
    print(f"timings of the last render ({result.timing_source}, ms): {passes}")
    print(f"adapter: {_adapter(renderer.adapter_info)}")
    print(f"stats: {json.dumps(result.stats)}")
    print(f"wrote {args.image} to {args.output}")
    return 0


def _progress(line: str) -> None:
    print(f"penumbra compare: {line}", file=sys.stderr, flush=True)


def _compare(args: argparse.Namespace) -> int:
    from penumbra.comparison import DEFAULT_SIZE, compare_methods
    from penumbra.metrics import summary

    scene = _scene(args, default_size=DEFAULT_SIZE)
    params = dict(_param(p) for p in args.param)
    c = compare_methods(
        scene, args.method, params=params, spp=args.spp, repeats=args.repeats,
        cache_dir=args.cache_dir, out=args.output, progress=None if args.quiet else _progress, truth=args.truth,
    )
    gt = c.ground_truth
    seconds = sum(gt.seconds.values()) + (sum(gt.second.seconds.values()) if gt.second else 0.0)
    print(f"scene {scene.name}, {_size(scene)}; adapter {_adapter(c.adapter)}")
    truth = "raytraced (the engine's own)" if gt.variant == "raytraced" else f"Mitsuba {gt.variant}"
    print(f"ground truth: {truth}, {gt.spp} spp, noise from a second seed; {seconds:.1f} s"
          f"{' (cached)' if all(gt.cached.values()) else ''}")
    print(f"times: {c.clock}; hard {c.baseline.warm_ms:.1f} ms")
    print(f"parameters: {json.dumps(params) if params else 'each method defaults'}")
    for note in c.notes:
        print(f"note: {note}")
    print()
    print(c.table())
    if len(c.rows) == 1:
        print()
        print(summary(c.rows[0].metrics))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(c.to_json(), f, indent=2)
    print(f"wrote the comparison to {args.output}")
    return 0


def _scene_arguments(parser: argparse.ArgumentParser, size_default: str) -> None:
    source = parser.add_mutually_exclusive_group()
    source.add_argument("--scene", default=scenes.DEFAULT, help=f"built-in scene (default {scenes.DEFAULT}; see `penumbra scenes`)")
    source.add_argument("--mesh", help="a mesh file trimesh can read, placed on the ground plane")
    parser.add_argument("--width", type=int, help=f"image width in pixels (default {size_default})")
    parser.add_argument("--height", type=int, help=f"image height in pixels (default {size_default})")
    parser.add_argument("--light-radius", type=float, help="override the light's radius")
    parser.add_argument("--param", action="append", default=[], metavar="KEY=VALUE", help="method parameter, repeatable")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="penumbra", description="Headless soft-shadow renderer.")
    sub = parser.add_subparsers(dest="command", required=True)

    render = sub.add_parser("render", help="render a built-in scene or a mesh file with one method, timed")
    _scene_arguments(render, "512")
    render.add_argument("--method", default="pcss", help="shadow method (default pcss; see `penumbra methods`)")
    render.add_argument("--repeats", type=int, default=DEFAULT_REPEATS,
                        help=f"timed renders after a warm-up; the warm time printed is their median (default {DEFAULT_REPEATS}; 0: render once, the first render's time)")
    render.add_argument("--image", default="radiance", help="which image to write (radiance, visibility, depth, ...)")
    render.add_argument("-o", "--output", default="penumbra.png", help="output file: .png (sRGB), .exr or .npy (linear)")
    render.set_defaults(run=_render)

    comp = sub.add_parser(
        "compare", help="every method (or those named) against Mitsuba ground truth: one picture, a table of error and warm time"
    )
    _scene_arguments(comp, "256")
    comp.add_argument("--method", action="append", help="a method to compare, repeatable (default: every implemented method)")
    comp.add_argument("--spp", type=int, default=1024, help="ground-truth samples per pixel (default 1024)")
    comp.add_argument(
        "--truth", choices=["mitsuba", "raytraced"], default="mitsuba",
        help="the ground truth: Mitsuba (default) or the engine's raytraced method at --spp light samples (give it thousands)",
    )
    comp.add_argument("--repeats", type=int, default=DEFAULT_REPEATS,
                      help=f"timed renders per method after a warm-up, fewer once they add up to {DEFAULT_BUDGET_S:g} s; times are their median (default {DEFAULT_REPEATS})")
    comp.add_argument("--cache-dir", help="ground-truth cache folder (default $PENUMBRA_CACHE_DIR or ~/.cache/penumbra)")
    comp.add_argument("--json", help="also write every figure to this JSON file")
    comp.add_argument("-q", "--quiet", action="store_true", help="no progress lines on stderr")
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

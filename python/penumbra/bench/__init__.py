"""``penumbra bench``: run time against error for every method, with Mitsuba
and the in-engine ``reference`` as peers, in one process.

A small TOML file (``benchmarks/bench.toml``) names the scenes, the image
size, the ground truth's samples, the repeats, a parameter grid per method,
the peers' sample counts and a scaling run; its ``[quick]`` table overrides
any of them for ``--quick`` (the CI run). For every scene x method x setting
the benchmark renders after a warm-up, takes the median time of ``repeats``
renders per pass and in total, and every SPEC metric against the cached
Mitsuba ground truth (with the ground truth's own noise from a second seed).
The peers run in the same process: Mitsuba's visibility estimator at a range
of rays per pixel (another seed than the ground truth's, not cached: timed)
and its radiance at the same spp, and ``reference`` at several sample counts.

Written to ``--out`` (default ``benchmarks/results/<config name>``):

- ``results.csv``: one row per configuration;
- ``pareto.png``: time against penumbra visibility RMSE, log-log, one curve
  per method (means over the scenes), peers included;
- ``pareto.md``: the Pareto-optimal settings of each method;
- ``ratios.md``: each method's time over ``hard``'s, and its best setting's
  time over the time ``reference`` and Mitsuba need for the same error;
- ``cost.md``: whether each setting's cost follows the penumbra: the
  median time of the shadow map and of the method's own passes, per 1000
  penumbra pixels, and the exponents of a log-log fit of its own passes'
  time against penumbra pixels and triangles over the scenes;
- ``halves.md``: where each setting's penumbra error lies: the median RMSE
  over the penumbra's inner half (ground truth under 1/2, mostly where the
  light's centre is hidden) and its outer half, and the inner half's share
  of the squared error;
- ``scaling.csv`` and ``scaling.png``: cost against image size and against
  penumbra area on screen (a light-radius sweep);
- ``table.md`` (with a ``table`` list of columns): one line per scene and
  configuration with those columns of ``results.csv``, a study's own table;
- ``time_to_error.md`` (with a ``[time_to_error]`` table): each curve's time
  to given penumbra RMSEs over the scenes (means or medians) and per scene,
  beside Mitsuba's;
- ``machine.md``: the machine, the adapter, the versions and the commit.

``--report`` renders nothing and writes the reports again from a finished
run's ``results.csv``. ``sampling_noise = true`` adds each row's own noise
(the configuration again at its seed + 1; Mitsuba's rows at another seed),
``resolution_error = k`` its RMSE against the same configuration at k times
its map size; a ``form`` in a scene table (``"soup"``, ...) hands the mesh
over in that form, a ``camera`` sets another view.

An entry of ``scenes`` is a scene name or a table of variants: ``{ scene =
"cube_on_plane", light_radius = [0.1, 0.4] }`` (a light-radius sweep),
``{ scene = ["mesh:spot.obj", "mesh:cube.obj"], setup = "wide_floor",
light_radius = 0.3 }`` (a mesh placed by :func:`penumbra.scenes.from_mesh`'s
``setup``), with ``label`` to name a single one; the results name each by its
label (``cube_on_plane r=0.1``, ``mesh:spot.obj wide_floor r=0.3``).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Sequence

from penumbra.bench.config import BenchConfig, SceneVariant, expand, label, load_config
from penumbra.bench import report
from penumbra.bench.report import *  # noqa: F403 (the reports, re-exported: report.__all__)
from penumbra.bench.runner import machine_description, make_renderer, run, run_scaling, write_reports
from penumbra.errors import ParameterError

__all__ = [
    "BenchConfig",
    "SceneVariant",
    "load_config",
    "expand",
    "label",
    "run",
    "run_scaling",
    "make_renderer",
    "machine_description",
    "write_reports",
    "main",
    "build_parser",
    "run_from_args",
]
__all__ += report.__all__


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser(argparse.ArgumentParser(prog="penumbra bench", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter))
    return run_from_args(parser.parse_args(argv))


def build_parser(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    parser.add_argument("--config", default="benchmarks/bench.toml", help="the benchmark config (default benchmarks/bench.toml)")
    parser.add_argument("--quick", action="store_true", help="apply the config's [quick] table (the CI run: a few minutes)")
    parser.add_argument("--out", help="output folder (default benchmarks/results/<config name>)")
    parser.add_argument("--fresh", action="store_true", help="ignore the rows of scenes an interrupted run finished (out/rows.jsonl)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="replace a top-level key of the config with a TOML value (repeatable): --set 'scenes=[\"cornell_box\"]' --set 'large={}'")
    parser.add_argument("--report", action="store_true", help="render nothing: write the reports again from the run's out/results.csv (after a change to the config's report keys)")
    return parser


def run_from_args(args: argparse.Namespace) -> int:
    cfg = load_config(args.config, quick=args.quick, overrides=args.set)
    out = Path(args.out or Path("benchmarks") / "results" / cfg.name)
    if args.report:
        if not (out / "results.csv").exists():
            raise ParameterError(f"--report reads {out / 'results.csv'}, which does not exist: run the benchmark first")
        rows = read_csv(out / "results.csv")
        for row in rows:  # a results.csv from before the [large] part has no size: all at the main one
            row.setdefault("size", f"{cfg.size}x{cfg.size}")
        print(f"wrote {out}/" + ", ".join(write_reports(cfg, out, rows)))
        return 0
    run(cfg, out, fresh=args.fresh)
    return 0

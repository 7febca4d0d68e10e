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
- ``scaling.csv`` and ``scaling.png``: cost against image size and against
  penumbra area on screen (a light-radius sweep);
- ``machine.md``: the machine, the adapter, the versions and the commit.
"""

from __future__ import annotations

import argparse
import csv
import itertools
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

import numpy as np

from penumbra import metrics, scenes
from penumbra import mitsuba as pm
from penumbra.errors import ParameterError
from penumbra.render import Renderer, RenderResult, methods
from penumbra.scene import Scene

__all__ = ["BenchConfig", "load_config", "run", "pareto_front", "time_at_error", "main"]

#: The metric the Pareto plot, the tables and the ratios use.
ERROR = "visibility_rmse_penumbra"

_KEYS = {
    "scenes": list,
    "size": int,
    "ground_truth_spp": int,
    "repeats": int,
    "warmup": int,
    "max_seconds_per_config": float,
    "methods": dict,
    "peers": dict,
    "scaling": dict,
}


@dataclass
class BenchConfig:
    """What to run (see ``benchmarks/bench.toml`` for every key)."""

    name: str
    scenes: list[str]
    size: int = 128
    ground_truth_spp: int = 1024
    repeats: int = 3
    warmup: int = 1
    #: After one timed render longer than this, no further repeats.
    max_seconds_per_config: float = 20.0
    #: method -> list of grids; a grid maps each parameter to a list of values
    #: (their product) or to one value.
    methods: dict[str, list[dict[str, Any]]] = field(default_factory=dict)
    #: ``mitsuba_spp`` (list) and ``reference_samples`` (list).
    peers: dict[str, Any] = field(default_factory=dict)
    #: ``scene``, ``methods`` (list), ``sizes`` (list), ``radii`` (list), ``ground_truth_spp``.
    scaling: dict[str, Any] = field(default_factory=dict)


def _checked(values: dict[str, Any], where: str) -> dict[str, Any]:
    for key, value in values.items():
        if key == "quick":
            continue
        if key not in _KEYS:
            raise ParameterError(f"{where}: unknown key {key!r} (known: {sorted(_KEYS)})")
        want = _KEYS[key]
        if want is float and isinstance(value, int) and not isinstance(value, bool):
            continue
        if not isinstance(value, want) or isinstance(value, bool):
            kind = {list: "a list", int: "an integer", float: "a number", dict: "a table"}[want]
            raise ParameterError(f"{where}: {key!r} must be {kind}, got {value!r}")
    for key in ("size", "ground_truth_spp", "repeats"):
        if key in values and values[key] < 1:
            raise ParameterError(f"{where}: {key!r} must be at least 1, got {values[key]}")
    if "warmup" in values and values["warmup"] < 0:
        raise ParameterError(f"{where}: 'warmup' must be at least 0, got {values['warmup']}")
    return values


def load_config(path: str | os.PathLike[str], quick: bool = False) -> BenchConfig:
    """Reads a benchmark config; ``quick`` applies its ``[quick]`` table."""
    path = Path(path)
    try:
        with open(path, "rb") as f:
            raw = tomllib.load(f)
    except OSError as e:
        raise ParameterError(f"cannot read the benchmark config {str(path)!r}: {e.strerror}") from e
    except tomllib.TOMLDecodeError as e:
        raise ParameterError(f"the benchmark config {str(path)!r} is not valid TOML: {e}") from e
    values = _checked(dict(raw), str(path))
    quick_values = values.pop("quick", {})
    if quick:
        values.update(_checked(dict(quick_values), f"{path} [quick]"))
    methods_ = values.get("methods", {})
    for method, grids in methods_.items():
        grids = [grids] if isinstance(grids, dict) else grids
        if not isinstance(grids, list) or not all(isinstance(g, dict) for g in grids):
            raise ParameterError(f"{path}: methods.{method} must be a table or a list of tables of parameters")
        methods_[method] = grids
    unknown = [s for s in values.get("scenes", []) if s not in scenes.names()]
    if unknown:
        raise ParameterError(f"{path}: unknown scenes {unknown} (built-in: {scenes.names()})")
    name = path.stem + ("_quick" if quick else "")
    return BenchConfig(name=name, **values)


def expand(grids: Iterable[dict[str, Any]]) -> list[dict[str, Any]]:
    """Every parameter set of the grids, in order, without repeats."""
    out: list[dict[str, Any]] = []
    for grid in grids:
        keys = list(grid)
        lists = [v if isinstance(v, list) else [v] for v in grid.values()]
        for combo in itertools.product(*lists):
            params = dict(zip(keys, combo))
            if params not in out:
                out.append(params)
    return out


def label(params: dict[str, Any]) -> str:
    """A short, stable name of a parameter set ("default" when empty)."""
    return " ".join(f"{k}={v}" for k, v in sorted(params.items())) or "default"


def pareto_front(points: Sequence[tuple[float, float]]) -> list[int]:
    """Indices of the (time, error) points no other point beats in both,
    sorted by time; ties in time keep the lower error."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front: list[int] = []
    best = math.inf
    for i in order:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def time_at_error(curve: Sequence[tuple[float, float]], error: float) -> tuple[float, str]:
    """The time a peer needs for ``error``, from its (time, error) points:
    interpolated log-log along its Pareto front. Returns (time, bound) where
    bound is ``"="``; ``"<="`` when even its cheapest point is at least this
    accurate (its time is an upper bound); ``">="`` when no point reaches the
    error (its most expensive time is a lower bound)."""
    points = [curve[i] for i in pareto_front(curve) if curve[i][0] > 0 and curve[i][1] > 0]
    if not points or not error > 0:
        return math.nan, "="
    if error >= points[0][1]:
        return points[0][0], "<="
    if error < points[-1][1]:
        return points[-1][0], ">="
    for (t0, e0), (t1, e1) in zip(points, points[1:]):
        if e1 <= error <= e0:
            # e0 > e1 > 0 on a front, so the log difference is positive.
            f = (math.log(e0) - math.log(error)) / (math.log(e0) - math.log(e1))
            return math.exp(math.log(t0) + f * (math.log(t1) - math.log(t0))), "="
    return points[-1][0], ">="  # unreachable: the front is monotone


def _median_render(renderer: Renderer, scene: Scene, method: str, params: dict[str, Any], cfg: BenchConfig) -> tuple[RenderResult, dict[str, float], int]:
    for _ in range(cfg.warmup):
        renderer.render(scene, method, **params)
    results = []
    for _ in range(cfg.repeats):
        results.append(renderer.render(scene, method, **params))
        if results[-1].total_ms > cfg.max_seconds_per_config * 1000:
            break
    passes = {name: statistics.median(r.timings.get(name, 0.0) for r in results) for name in results[-1].timings}
    passes["total"] = statistics.median(r.total_ms for r in results)
    return results[-1], passes, len(results)


def _mitsuba_ms(scene: Scene, spp: int, kind: str, cfg: BenchConfig) -> tuple[float, dict[str, np.ndarray], int]:
    times = []
    images: dict[str, np.ndarray] = {}
    for _ in range(cfg.repeats):
        peer = pm.ground_truth(scene, spp=spp, seed=2, kinds=[kind], cache=False)
        times.append(peer.seconds[kind] * 1000.0)
        images = peer.images
        if times[-1] > cfg.max_seconds_per_config * 1000:
            break
    return statistics.median(times), images, len(times)


def make_renderer() -> Renderer:
    """A renderer timed with GPU timestamps on hardware and CPU clocks on a
    software adapter (lavapipe's timestamps of a command buffer's last pass
    are unreliable); every pass is recomputed on every render."""
    from penumbra.render import adapter_info

    timing = "cpu" if adapter_info().get("is_software") else "auto"
    return Renderer(timing, pass_cache=False)


def run(cfg: BenchConfig, out: str | os.PathLike[str], log: Callable[[str], None] = print) -> list[dict[str, Any]]:
    """Runs the benchmark and writes its outputs under ``out``; returns the rows."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    renderer = make_renderer()
    start = time.perf_counter()
    commit = _commit()  # before the run: what was measured
    rows: list[dict[str, Any]] = []
    implemented = methods()
    unknown = [m for m in cfg.methods if m not in implemented]
    if unknown:
        raise ParameterError(f"config {cfg.name}: methods {unknown} are not implemented (implemented: {implemented})")
    for scene_name in cfg.scenes:
        scene = scenes.get(scene_name, width=cfg.size, height=cfg.size)
        gt = pm.ground_truth(scene, spp=cfg.ground_truth_spp, noise_seed=1)
        configs: list[tuple[str, str, dict[str, Any]]] = [("method", "hard", {})]
        for method, grids in cfg.methods.items():
            configs += [("method", method, p) for p in expand(grids) if (method, p) != ("hard", {})]
        configs += [("peer", "reference", {"n_samples": n}) for n in cfg.peers.get("reference_samples", [])]
        hard_ms = math.nan
        object_id = None
        for kind, method, params in configs:
            result, passes, repeats = _median_render(renderer, scene, method, params, cfg)
            row: dict[str, Any] = {
                "scene": scene_name, "kind": kind, "method": method, "label": label(params),
                "params": json.dumps(result.params, sort_keys=True), "repeats": repeats,
                "timing_source": result.timing_source, "total_ms": passes.pop("total"),
            }
            if method == "hard" and not params:
                hard_ms = row["total_ms"]
            row["time_over_hard"] = row["total_ms"] / hard_ms
            row.update({f"ms_{k}": v for k, v in passes.items()})
            row.update(metrics.compare(result, gt))
            object_id = result.object_id
            row.update({f"stat_{k}": v for k, v in result.stats.items()})
            rows.append(row)
            log(f"{scene_name:20s} {method:9s} {row['label']:50.50s} {row['total_ms']:9.1f} ms  x{row['time_over_hard']:6.2f} hard  penumbra RMSE {row[ERROR]:.4f}")
        spps = cfg.peers.get("mitsuba_spp", [])
        if spps:
            pm.ground_truth(scene, spp=min(spps), seed=2, kinds=["visibility", "radiance"], cache=False)  # warm-up: Dr.Jit compiles its kernels
        for spp in spps:
            vis_ms, images, repeats = _mitsuba_ms(scene, spp, "visibility", cfg)
            rad_ms, rad, _ = _mitsuba_ms(scene, spp, "radiance", cfg)
            # The same silhouette pixels left out of the radiance metrics as for the methods.
            m = metrics.compare_images(images["visibility"], gt, radiance=rad["radiance"], object_id=object_id)
            row = {
                "scene": scene_name, "kind": "peer", "method": "mitsuba", "label": f"spp={spp}",
                "params": json.dumps({"spp": spp, "variant": pm.variant()}), "repeats": repeats,
                "timing_source": "cpu_clock", "total_ms": vis_ms, "time_over_hard": vis_ms / hard_ms,
                "ms_visibility": vis_ms, "ms_radiance": rad_ms, **m,
            }
            rows.append(row)
            log(f"{scene_name:20s} mitsuba   {row['label']:50.50s} {vis_ms:9.1f} ms  x{row['time_over_hard']:6.2f} hard  penumbra RMSE {row[ERROR]:.4f}")
    _write_csv(out / "results.csv", rows)
    summary = aggregate(rows)
    (out / "pareto.md").write_text(pareto_table(summary))
    (out / "ratios.md").write_text(ratio_tables(rows, summary))
    plot_pareto(summary, out / "pareto.png", f"{cfg.name}: {cfg.size}x{cfg.size}, means over {len(cfg.scenes)} scene(s)")
    scaling_rows = run_scaling(cfg, renderer, log) if cfg.scaling else []
    if scaling_rows:
        _write_csv(out / "scaling.csv", scaling_rows)
        plot_scaling(scaling_rows, out / "scaling.png")
    (out / "machine.md").write_text(machine_description(renderer, cfg, time.perf_counter() - start, commit))
    log((out / "ratios.md").read_text())
    log(f"wrote {out}/results.csv, pareto.png, pareto.md, ratios.md, machine.md" + (", scaling.csv, scaling.png" if scaling_rows else ""))
    return rows


def _write_csv(path: Path, rows: list[dict[str, Any]]) -> None:
    columns: list[str] = []
    for row in rows:
        columns += [k for k in row if k not in columns]
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=columns)
        writer.writeheader()
        writer.writerows(rows)


@dataclass
class Point:
    """One configuration averaged over the scenes."""

    method: str
    label: str
    kind: str
    ms: float
    time_over_hard: float
    error: float


def aggregate(rows: list[dict[str, Any]]) -> list[Point]:
    """Means over the scenes of each (method, setting): time, time over
    ``hard`` and penumbra visibility RMSE."""
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for row in rows:
        groups.setdefault((row["method"], row["label"]), []).append(row)
    return [
        Point(method, lab, g[0]["kind"], float(np.mean([r["total_ms"] for r in g])),
              float(np.mean([r["time_over_hard"] for r in g])), float(np.mean([r[ERROR] for r in g])))
        for (method, lab), g in groups.items()
    ]


def _by_method(points: list[Point]) -> dict[str, list[Point]]:
    out: dict[str, list[Point]] = {}
    for p in points:
        out.setdefault(p.method, []).append(p)
    return out


def pareto_table(points: list[Point]) -> str:
    """The markdown table of each method's Pareto-optimal settings."""
    lines = ["| method | setting | time (ms) | time / hard | penumbra visibility RMSE |", "|---|---|---|---|---|"]
    for method, group in _by_method(points).items():
        for i in pareto_front([(p.ms, p.error) for p in group]):
            p = group[i]
            lines.append(f"| {method} | {p.label} | {p.ms:.1f} | {p.time_over_hard:.2f} | {p.error:.4f} |")
    return "\n".join(lines) + "\n"


def _ratio(t: float, peer: tuple[float, str]) -> str:
    peer_t, bound = peer
    if not math.isfinite(peer_t) or peer_t <= 0:
        return "n/a"
    # The method's time over the peer's: a bound on the peer's time flips.
    flip = {"=": "", "<=": "≥ ", ">=": "≤ "}[bound]
    return f"{flip}{t / peer_t:.3g}"


def ratio_tables(rows: list[dict[str, Any]], points: list[Point]) -> str:
    """Each method's best setting (lowest error) against the peers at the
    same error, over the scene means and per scene."""
    peers = {m: [(p.ms, p.error) for p in points if p.method == m] for m in ("reference", "mitsuba")}
    lines = [
        "Means over the scenes. Best setting: the lowest penumbra visibility RMSE. The peers' times at that error are",
        "interpolated log-log along their Pareto fronts; ≥ / ≤ mark bounds where a peer's tested range does not reach it.",
        "",
        "| method | best setting | penumbra RMSE | time (ms) | time / hard | time / reference at equal error | time / Mitsuba at equal error |",
        "|---|---|---|---|---|---|---|",
    ]
    for method, group in _by_method(points).items():
        if method == "mitsuba":
            continue
        best = min(group, key=lambda p: p.error)
        lines.append(
            f"| {method} | {best.label} | {best.error:.4f} | {best.ms:.1f} | {best.time_over_hard:.2f} | "
            f"{_ratio(best.ms, time_at_error(peers['reference'], best.error))} | {_ratio(best.ms, time_at_error(peers['mitsuba'], best.error))} |"
        )
    lines += ["", "Per scene:", "", "| scene | method | best setting | penumbra RMSE | time / hard | time / reference | time / Mitsuba |", "|---|---|---|---|---|---|---|"]
    for scene in dict.fromkeys(r["scene"] for r in rows):
        here = [r for r in rows if r["scene"] == scene]
        curves = {m: [(r["total_ms"], r[ERROR]) for r in here if r["method"] == m] for m in ("reference", "mitsuba")}
        for method in dict.fromkeys(r["method"] for r in here):
            if method == "mitsuba":
                continue
            best_row = min((r for r in here if r["method"] == method), key=lambda r: r[ERROR])
            lines.append(
                f"| {scene} | {method} | {best_row['label']} | {best_row[ERROR]:.4f} | {best_row['time_over_hard']:.2f} | "
                f"{_ratio(best_row['total_ms'], time_at_error(curves['reference'], best_row[ERROR]))} | "
                f"{_ratio(best_row['total_ms'], time_at_error(curves['mitsuba'], best_row[ERROR]))} |"
            )
    return "\n".join(lines) + "\n"


def plot_pareto(points: list[Point], path: Path, title: str) -> None:
    """Time against penumbra visibility RMSE, log-log: every setting as a dot,
    each method's Pareto front as a line, peers dashed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5.5))
    for method, group in _by_method(points).items():
        xy = [(p.ms, p.error) for p in group]
        front = [xy[i] for i in pareto_front(xy)]
        peer = group[0].kind == "peer"
        (line,) = ax.plot([t for t, _ in front], [e for _, e in front], "--" if peer else "-", marker="o", label=method)
        ax.scatter([t for t, _ in xy], [e for _, e in xy], s=10, color=line.get_color(), alpha=0.4)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("time per render (ms)")
    ax.set_ylabel("penumbra visibility RMSE vs ground truth")
    ax.set_title(title, fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def run_scaling(cfg: BenchConfig, renderer: Renderer, log: Callable[[str], None] = print) -> list[dict[str, Any]]:
    """Cost against image size, and against penumbra area on screen (a sweep
    of the light's radius at the config's size; the penumbra pixels counted
    on Mitsuba's visibility)."""
    s = cfg.scaling
    name = s.get("scene", scenes.DEFAULT)
    rows: list[dict[str, Any]] = []
    runs = [("size", size, None) for size in s.get("sizes", [])] + [("radius", cfg.size, r) for r in s.get("radii", [])]
    for sweep, size, radius in runs:
        scene = scenes.get(name, width=size, height=size, light_radius=radius)
        penumbra_pixels = math.nan
        if sweep == "radius":
            gt = pm.ground_truth(scene, spp=int(s.get("ground_truth_spp", 64)), kinds=["visibility"])
            penumbra_pixels = int(metrics.penumbra_region(gt.visibility).sum())
        for method in s.get("methods", ["hard"]):
            result, passes, repeats = _median_render(renderer, scene, method, {}, cfg)
            row: dict[str, Any] = {
                "sweep": sweep, "scene": name, "method": method, "size": size, "pixels": size * size,
                "light_radius": scene.light.radius, "penumbra_pixels": penumbra_pixels,
                "repeats": repeats, "total_ms": passes.pop("total"),
            }
            row.update({f"ms_{k}": v for k, v in passes.items()})
            row.update({f"stat_{k}": v for k, v in result.stats.items()})
            rows.append(row)
            log(f"scaling {sweep}={size if sweep == 'size' else radius}: {method:9s} {row['total_ms']:9.1f} ms")
    return rows


def plot_scaling(rows: list[dict[str, Any]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    for ax, sweep, x, xlabel in ((axes[0], "size", "pixels", "image pixels"), (axes[1], "radius", "penumbra_pixels", "penumbra pixels on screen (light radius sweep)")):
        for method in dict.fromkeys(r["method"] for r in rows):
            pts = sorted((r[x], r["total_ms"]) for r in rows if r["sweep"] == sweep and r["method"] == method)
            if pts:
                ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", label=method)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(xlabel)
        ax.set_ylabel("time per render (ms)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _commit() -> str:
    here = Path(__file__).resolve().parent
    try:
        sha = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=here, capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown (not a git checkout)"
    return sha + (" (with uncommitted changes)" if dirty else "")


def _cpu() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def machine_description(renderer: Renderer, cfg: BenchConfig, seconds: float, commit: str) -> str:
    import mitsuba

    import penumbra

    info = renderer.adapter_info
    memory = "unknown"
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal"):
                memory = f"{int(line.split()[1]) / 2**20:.1f} GiB"
    except OSError:
        pass
    lines = [
        f"# Benchmark `{cfg.name}`",
        "",
        f"- commit: {commit}",
        f"- finished: {time.strftime('%Y-%m-%d %H:%M %Z')}",
        f"- machine: {platform.platform()}; CPU {_cpu()}, {os.cpu_count()} logical cores; memory {memory}",
        f"- adapter: {info.get('name')} ({info.get('backend')}, {info.get('device_type')}, {info.get('driver_info')}); software: {info.get('is_software')}",
        f"- timing: {renderer.timing_source} (GPU timestamps on hardware; CPU clocks around each pass on a software adapter)",
        f"- Mitsuba {mitsuba.__version__}, variant {pm.variant()}, on the CPU",
        f"- penumbra {penumbra.__version__}, numpy {np.__version__}, Python {sys.version.split()[0]}",
        f"- config: scenes {cfg.scenes}, {cfg.size}x{cfg.size}, ground truth {cfg.ground_truth_spp} spp (noise from a second seed), "
        f"warm-up {cfg.warmup}, median of {cfg.repeats} renders (fewer past {cfg.max_seconds_per_config:g} s)",
        f"- wall time of the whole run: {seconds / 60:.1f} min",
    ]
    return "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser(argparse.ArgumentParser(prog="penumbra bench", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter))
    return run_from_args(parser.parse_args(argv))


def build_parser(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    parser.add_argument("--config", default="benchmarks/bench.toml", help="the benchmark config (default benchmarks/bench.toml)")
    parser.add_argument("--quick", action="store_true", help="apply the config's [quick] table (the CI run: a few minutes)")
    parser.add_argument("--out", help="output folder (default benchmarks/results/<config name>)")
    return parser


def run_from_args(args: argparse.Namespace) -> int:
    cfg = load_config(args.config, quick=args.quick)
    out = args.out or str(Path("benchmarks") / "results" / cfg.name)
    run(cfg, out)
    return 0


if __name__ == "__main__":
    from penumbra.errors import PenumbraError

    try:
        sys.exit(main())
    except PenumbraError as e:
        print(f"penumbra bench: error: {e}", file=sys.stderr)
        sys.exit(2)

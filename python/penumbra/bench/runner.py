"""``penumbra bench`` runs: every scene x method x setting timed after a
warm-up (medians over repeats), measured against cached Mitsuba ground
truth, the peers (Mitsuba's estimator, ``reference``) and the scaling runs."""

from __future__ import annotations

import hashlib
import importlib
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from penumbra import metrics, scenes
from penumbra import mitsuba as pm
from penumbra.bench.config import BenchConfig, expand, label
from penumbra.bench.report import ERROR, aggregate, cost_tables, halves_tables, markdown_table, pareto_table, plot_pareto, plot_scaling, ratio_tables, suite_tables, time_at_error, time_to_error_tables, what_to_use, write_csv
from penumbra.errors import GpuFeatureError, ParameterError, PenumbraError, SceneError
from penumbra.grid import result_columns
from penumbra.render import Renderer, RenderResult, method_info, methods
from penumbra.scene import Scene

__all__ = ["run", "write_reports", "run_scaling", "make_renderer", "machine_description", "parts", "Part", "with_mitsuba_ratios", "MITSUBA_RULE"]


#: What the rows are computed from: the metrics read visibility, radiance and object ids.
OUTPUTS = ["radiance", "visibility", "object_id"]


def render_outputs(cfg: BenchConfig) -> list[str]:
    """The images a timed render reads back. With ``radiance = false`` the
    question is visibility alone, as Mitsuba's peer rows answer it: no
    radiance, so no shading pass and no radiance readback in the time (until
    issue 30 every render shaded, 43 of `hard`'s 174 ms at 1920x1080). A
    config's own ``columns`` may read anything: they get every image."""
    if cfg.columns:
        return OUTPUTS + ["position", "normal"]
    return OUTPUTS if cfg.radiance else ["visibility", "object_id"]


def _median_render(renderer: Renderer, scene: Scene, method: str, params: dict[str, Any], cfg: BenchConfig) -> tuple[RenderResult, dict[str, float], int]:
    outputs = render_outputs(cfg)
    for _ in range(cfg.warmup):
        renderer.render(scene, method, outputs=outputs, **params)
    results = []
    for _ in range(cfg.repeats):
        results.append(renderer.render(scene, method, outputs=outputs, **params))
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


@dataclass
class Part:
    """One size of the run: its scenes, image size, ground truth and grids."""

    name: str
    scenes: list[str]
    width: int
    height: int
    ground_truth_spp: int
    methods: dict[str, list[dict[str, Any]]]
    peers: dict[str, Any]
    sampling_noise: bool = False
    resolution_error: int = 0


def parts(cfg: BenchConfig) -> list[Part]:
    """The run's parts: the main one at ``size`` and, with a ``[large]``
    table, its scenes at its ``width`` x ``height`` (its own ``methods``,
    ``peers`` and ``ground_truth_spp`` where given, else the main ones)."""
    out = [Part("main", cfg.scenes, cfg.size, cfg.size, cfg.ground_truth_spp, cfg.methods, cfg.peers, cfg.sampling_noise, cfg.resolution_error)]
    if cfg.large:
        big = cfg.large
        out.append(Part("large", list(big["scenes"]), int(big["width"]), int(big["height"]), int(big.get("ground_truth_spp", cfg.ground_truth_spp)),
                        big.get("methods", cfg.methods), big.get("peers", cfg.peers), big.get("sampling_noise", cfg.sampling_noise),
                        big.get("resolution_error", cfg.resolution_error)))
    return out


def _scene_rows(renderer: Renderer, cfg: BenchConfig, part: Part, scene_name: str, log: Callable[[str], None]) -> list[dict[str, Any]]:
    """Every configuration and peer of one scene of ``part``, each row with
    its time over Mitsuba's at the same error (see :func:`with_mitsuba_ratios`)."""
    scene = cfg.scene(scene_name, part.width, part.height)
    kinds = ["radiance", "visibility"] if cfg.radiance else ["visibility"]
    gt = pm.ground_truth(scene, spp=part.ground_truth_spp, noise_seed=1, kinds=kinds)
    size = f"{part.width}x{part.height}"
    configs: list[tuple[str, str, dict[str, Any]]] = [("method", "hard", {})]
    for method, grids in part.methods.items():
        configs += [("method", method, p) for p in expand(grids) if (method, p) != ("hard", {})]
    configs += [("peer", "reference", {"n_samples": n}) for n in part.peers.get("reference_samples", [])]
    hard_ms = math.nan
    object_id = None
    rows: list[dict[str, Any]] = []
    done: dict[tuple[str, str], tuple[dict[str, Any], dict[str, Any], np.ndarray]] = {}  # (method, label) -> grid params, row, visibility
    for kind, method, params in configs:
        try:
            result, passes, repeats = _median_render(renderer, scene, method, params, cfg)
        except (SceneError, GpuFeatureError) as e:
            # A scene a method or setting refuses (a frustum over a wide floor, maps past the adapter's limits).
            rows.append({"scene": scene_name, "size": size, "kind": "refused", "method": method, "label": label(params), "refused": str(e)})
            log(f"{scene_name[:30]:30s} {method:9s} {label(params):40.40s} refused: {e}")
            continue
        total = passes.pop("total")
        if method == "hard" and not params:
            hard_ms = total
        row: dict[str, Any] = {
            "scene": scene_name, "size": size, "kind": kind, "method": method, "label": label(params),
            "params": json.dumps(result.params, sort_keys=True), "repeats": repeats,
            "time_over_hard": total / hard_ms,
            # The row schema sweeps share, with the medians over the repeats.
            **result_columns(result, timings=passes, total_ms=total),
        }
        row.update(metrics.compare(result, gt))
        row.update(_own_errors(renderer, scene, method, params, result, gt, part))
        for name in cfg.columns:
            module, _, function = name.partition(":")
            row.update(getattr(importlib.import_module(module), function)(result, scene))
        object_id = result.object_id
        rows.append(row)
        done[(method, label(params))] = (params, row, result.visibility)
        log(f"{scene_name[:30]:30s} {method:9s} {row['label']:40.40s} {row['total_ms']:9.1f} ms  x{row['time_over_hard']:6.2f} hard  penumbra RMSE {row[ERROR]:.4f}")
    for params, row, visibility in list(done.values()):
        for name, entry in {**cfg.against.get("*", {}), **cfg.against.get(row["method"], {})}.items():
            row.update(_against(renderer, scene, row, params, visibility, name, entry, done, gt, object_id))
    spps = part.peers.get("mitsuba_spp", [])
    if spps:
        pm.ground_truth(scene, spp=min(spps), seed=2, kinds=kinds, cache=False)  # warm-up: Dr.Jit compiles its kernels
    for spp in spps:
        vis_ms, images, repeats = _mitsuba_ms(scene, spp, "visibility", cfg)
        rad_ms, rad = math.nan, dict[str, np.ndarray]()
        if cfg.radiance:
            rad_ms, rad, _ = _mitsuba_ms(scene, spp, "radiance", cfg)
        # The same silhouette pixels left out of the radiance metrics as for the methods.
        m = metrics.compare_images(images["visibility"], gt, radiance=rad.get("radiance"), object_id=object_id)
        row = {
            "scene": scene_name, "size": size, "kind": "peer", "method": "mitsuba", "label": f"spp={spp}",
            "params": json.dumps({"spp": spp, "variant": pm.variant()}), "repeats": repeats,
            "timing_source": "cpu_clock", "total_ms": vis_ms, "time_over_hard": vis_ms / hard_ms,
            "ms_visibility": vis_ms, "ms_radiance": rad_ms, **m,
        }
        if part.sampling_noise:
            again = pm.ground_truth(scene, spp=spp, seed=3, kinds=kinds, cache=False).images
            both = (rad["radiance"], again["radiance"]) if cfg.radiance else None
            noise = metrics.own_noise((images["visibility"], again["visibility"]), gt, radiance=both, object_id=object_id)
            row.update({f"sampling_noise_{k}": v for k, v in noise.items()})
        rows.append(row)
        log(f"{scene_name[:30]:30s} mitsuba   {row['label']:40.40s} {vis_ms:9.1f} ms  x{row['time_over_hard']:6.2f} hard  penumbra RMSE {row[ERROR]:.4f}")
    return with_mitsuba_ratios(rows)


def _against(renderer: Renderer, scene: Scene, row: dict[str, Any], params: dict[str, Any], visibility: np.ndarray, name: str, entry: dict[str, Any],
             done: dict[tuple[str, str], tuple[dict[str, Any], dict[str, Any], np.ndarray]], gt: pm.GroundTruth, object_id: np.ndarray | None) -> dict[str, float]:
    """The ``vs_<name>_*`` columns of one row (:attr:`BenchConfig.against`):
    its visibility against the configuration ``entry`` names, that row's
    image where the run has it, else rendered for the purpose."""
    method = entry.get("method", row["method"])
    keep = entry.get("keep")
    other = {**{k: v for k, v in params.items() if keep is None or k in keep}, **entry.get("set", {})}
    when = entry.get("when", {})
    if (method, other) == (row["method"], params) or any(params.get(k) != v for k, v in when.items()) or not set(other) <= set(method_info(method).defaults()):
        return {}  # itself; a row the entry is not for; a parameter the method does not take (a seed for hard)
    found = done.get((method, label(other)))
    try:
        theirs = found[2] if found else renderer.render(scene, method, outputs=OUTPUTS, **other).visibility
    except PenumbraError:  # a configuration the scene or the adapter refuses (maps past its limits)
        return {}
    threshold = entry.get("threshold", 0.01)
    if threshold == "one_sample":  # one sample's weight, and float rounding
        threshold = 1.0 / float(json.loads(row["params"])["n_samples"]) + 1e-6
    geometry = object_id >= 0 if object_id is not None else np.ones(visibility.shape, dtype=bool)
    d = np.abs(visibility.astype(np.float64) - theirs)
    out = {"max": float(d[geometry].max()), "mean": float(d[geometry].mean()), "rmse": metrics.rmse(visibility, theirs, geometry),
           "rmse_penumbra": metrics.rmse(visibility, theirs, metrics.penumbra_region(gt.visibility)), "over": float((d[geometry] > threshold).sum())}
    if found:
        out["time"] = float(row["total_ms"]) / float(found[1]["total_ms"])
    return {f"vs_{name}_{k}": v for k, v in out.items()}


def _own_errors(renderer: Renderer, scene: Scene, method: str, params: dict[str, Any], result: RenderResult, gt: pm.GroundTruth, part: Part) -> dict[str, float]:
    """A row's own noise (the same configuration at its seed + 1) and
    resolution error (at ``resolution_error`` times its map size), where the
    part asks for them and the method has a seed or a map size."""
    out: dict[str, float] = {}
    if part.sampling_noise and "seed" in result.params:
        again = renderer.render(scene, method, outputs=OUTPUTS, **{**params, "seed": int(result.params["seed"]) + 1})
        noise = metrics.own_noise((result.visibility, again.visibility), gt, radiance=(result.radiance, again.radiance), object_id=result.object_id)
        out.update({f"sampling_noise_{k}": v for k, v in noise.items()})
    if part.resolution_error and isinstance(result.params.get("map_size"), int):
        finer = renderer.render(scene, method, outputs=OUTPUTS, **{**params, "map_size": part.resolution_error * int(result.params["map_size"])}).visibility
        out["resolution_error_visibility_rmse"] = metrics.rmse(result.visibility, finer)
        out["resolution_error_visibility_rmse_penumbra"] = metrics.rmse(result.visibility, finer, metrics.penumbra_region(gt.visibility))
    return out


#: How a row's time is set against Mitsuba's (the rule the report states).
MITSUBA_RULE = (
    "time over Mitsuba's at equal error: the row's time over the time Mitsuba's visibility estimator needs on the same scene "
    "for the row's penumbra RMSE, interpolated log-log along that scene's Mitsuba curve (its Pareto front over the spp run); "
    "where the row is more accurate than Mitsuba's most samples, Mitsuba's time is a lower bound and the ratio an upper one (<=), "
    "where it is less accurate than Mitsuba's fewest, the ratio is a lower bound (>=)"
)


def with_mitsuba_ratios(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Adds ``mitsuba_ms_at_equal_error``, ``time_over_mitsuba`` and
    ``mitsuba_bound`` (``=``, ``<=``, ``>=`` on the ratio) to every row of one
    scene that is not Mitsuba's (:data:`MITSUBA_RULE`)."""
    curve = [(float(r["total_ms"]), float(r[ERROR])) for r in rows if r["method"] == "mitsuba"]
    if not curve:
        return rows
    for r in rows:
        if r["method"] == "mitsuba" or r["kind"] == "refused":
            continue
        t, bound = time_at_error(curve, float(r[ERROR]))
        r["mitsuba_ms_at_equal_error"] = t
        r["time_over_mitsuba"] = float(r["total_ms"]) / t if t > 0 else math.nan
        # A bound on Mitsuba's time flips on the ratio.
        r["mitsuba_bound"] = {"=": "=", "<=": ">=", ">=": "<="}[bound]
    return rows


def _key(cfg: BenchConfig, part: Part, scene_name: str, commit: str) -> str:
    """What a cached scene's rows depend on: the commit, the scene, its part's
    size, truth, grids and peers, and the timing settings."""
    variant = cfg.variants.get(scene_name)
    text = json.dumps([commit, scene_name, repr(variant) if variant else None, part.width, part.height, part.ground_truth_spp, part.methods, part.peers,
                       part.sampling_noise, part.resolution_error, cfg.against, cfg.columns,
                       cfg.repeats, cfg.warmup, cfg.max_seconds_per_config, cfg.radiance], sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def _load_done(path: Path) -> dict[str, list[dict[str, Any]]]:
    done: dict[str, list[dict[str, Any]]] = {}
    if path.exists():
        for line in path.read_text().splitlines():
            try:
                entry = json.loads(line)
            except json.JSONDecodeError:
                continue  # a line cut by an interruption
            done[entry["key"]] = entry["rows"]
    return done


def run(cfg: BenchConfig, out: str | os.PathLike[str], log: Callable[[str], None] = print, fresh: bool = False) -> list[dict[str, Any]]:
    """Runs the benchmark and writes its outputs under ``out``; returns the
    rows. Each finished scene's rows are appended to ``out/rows.jsonl``: a run
    interrupted and started again with the same commit and config reuses
    them (``fresh`` ignores them)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    renderer = make_renderer()
    start = time.perf_counter()
    commit = _commit()  # before the run: what was measured
    implemented = methods()
    for part in parts(cfg):
        unknown = [m for m in part.methods if m not in implemented]
        if unknown:
            raise ParameterError(f"config {cfg.name}: methods {unknown} are not implemented (implemented: {implemented})")
    cache = out / "rows.jsonl"
    if fresh and cache.exists():
        cache.unlink()
    done = _load_done(cache)
    todo = [(part, name) for part in parts(cfg) for name in part.scenes]
    rows: list[dict[str, Any]] = []
    for i, (part, scene_name) in enumerate(todo, 1):
        key = _key(cfg, part, scene_name, commit)
        elapsed = time.perf_counter() - start
        log(f"[{i}/{len(todo)}] {scene_name} at {part.width}x{part.height} ({elapsed / 60:.1f} min so far)" + (": cached" if key in done else ""))
        if key not in done:
            done[key] = _scene_rows(renderer, cfg, part, scene_name, log)
            with open(cache, "a") as f:
                f.write(json.dumps({"key": key, "rows": done[key]}, default=float) + "\n")
        rows += done[key]
    refused = [r for r in rows if r["kind"] == "refused"]
    rows = [r for r in rows if r["kind"] != "refused"]
    if refused:
        (out / "refused.md").write_text("".join(f"- {r['scene']} {r['size']} {r['method']} {r['label']}: {r['refused']}\n" for r in refused))
    write_csv(out / "results.csv", rows)
    written = write_reports(cfg, out, rows)
    scaling_rows = run_scaling(cfg, renderer, log) if cfg.scaling else []
    if scaling_rows:
        write_csv(out / "scaling.csv", scaling_rows)
        plot_scaling(scaling_rows, out / "scaling.png")
    (out / "machine.md").write_text(machine_description(renderer, cfg, time.perf_counter() - start, commit))
    log((out / "suite.md").read_text())
    log(f"wrote {out}/results.csv, {', '.join(written)}, machine.md" + (", scaling.csv, scaling.png" if scaling_rows else ""))
    return rows


def write_reports(cfg: BenchConfig, out: Path, rows: list[dict[str, Any]]) -> list[str]:
    """Every report of ``rows`` (a run's, or its ``results.csv`` read back:
    ``penumbra bench --report``) under ``out``; returns the files' names."""
    main_rows = [r for r in rows if r["size"] == f"{cfg.size}x{cfg.size}"]
    summary = aggregate(main_rows)
    reports = {
        "suite.md": suite_tables(rows) + "\n" + what_to_use(rows) + "\n" + MITSUBA_RULE[0].upper() + MITSUBA_RULE[1:] + ".\n",
        "pareto.md": pareto_table(summary),
        "ratios.md": ratio_tables(main_rows, summary),
        "cost.md": cost_tables(rows),
    }
    halves = halves_tables(rows)
    if halves:
        reports["halves.md"] = halves
    if cfg.table:
        reports["table.md"] = markdown_table(rows, cfg.table)
    if cfg.time_to_error:
        tte = cfg.time_to_error
        reports["time_to_error.md"] = time_to_error_tables(main_rows, tte["errors"], tte.get("aggregate", "median"), tte.get("split", []))
    for name, text in reports.items():
        (out / name).write_text(text)
    plot_pareto(summary, out / "pareto.png", f"{cfg.name}: {cfg.size}x{cfg.size}, medians over {len(cfg.scenes)} scene(s)")
    return [*reports, "pareto.png"]


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
            total = passes.pop("total")
            row: dict[str, Any] = {
                "sweep": sweep, "scene": name, "method": method, "size": size, "pixels": size * size,
                "light_radius": scene.light.radius, "penumbra_pixels": penumbra_pixels,
                "repeats": repeats, **result_columns(result, timings=passes, total_ms=total),
            }
            rows.append(row)
            log(f"scaling {sweep}={size if sweep == 'size' else radius}: {method:9s} {row['total_ms']:9.1f} ms")
    return rows


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

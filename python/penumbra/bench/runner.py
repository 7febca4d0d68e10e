"""``penumbra bench`` runs: every scene x method x setting timed after a
warm-up (medians over repeats), measured against cached Mitsuba ground
truth, the peers (Mitsuba's estimator, ``reference``) and the scaling runs."""

from __future__ import annotations

import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

from penumbra import metrics, scenes
from penumbra import mitsuba as pm
from penumbra.bench.config import BenchConfig, expand, label
from penumbra.bench.report import ERROR, aggregate, pareto_table, plot_pareto, plot_scaling, ratio_tables, write_csv
from penumbra.errors import ParameterError
from penumbra.grid import result_columns
from penumbra.render import Renderer, RenderResult, methods
from penumbra.scene import Scene

__all__ = ["run", "run_scaling", "make_renderer", "machine_description"]


#: What the rows are computed from: the metrics read visibility, radiance and object ids.
OUTPUTS = ["radiance", "visibility", "object_id"]


def _median_render(renderer: Renderer, scene: Scene, method: str, params: dict[str, Any], cfg: BenchConfig) -> tuple[RenderResult, dict[str, float], int]:
    for _ in range(cfg.warmup):
        renderer.render(scene, method, outputs=OUTPUTS, **params)
    results = []
    for _ in range(cfg.repeats):
        results.append(renderer.render(scene, method, outputs=OUTPUTS, **params))
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
            total = passes.pop("total")
            if method == "hard" and not params:
                hard_ms = total
            row: dict[str, Any] = {
                "scene": scene_name, "kind": kind, "method": method, "label": label(params),
                "params": json.dumps(result.params, sort_keys=True), "repeats": repeats,
                "time_over_hard": total / hard_ms,
                # The row schema sweeps share, with the medians over the repeats.
                **result_columns(result, timings=passes, total_ms=total),
            }
            row.update(metrics.compare(result, gt))
            object_id = result.object_id
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
    write_csv(out / "results.csv", rows)
    summary = aggregate(rows)
    (out / "pareto.md").write_text(pareto_table(summary))
    (out / "ratios.md").write_text(ratio_tables(rows, summary))
    plot_pareto(summary, out / "pareto.png", f"{cfg.name}: {cfg.size}x{cfg.size}, means over {len(cfg.scenes)} scene(s)")
    scaling_rows = run_scaling(cfg, renderer, log) if cfg.scaling else []
    if scaling_rows:
        write_csv(out / "scaling.csv", scaling_rows)
        plot_scaling(scaling_rows, out / "scaling.png")
    (out / "machine.md").write_text(machine_description(renderer, cfg, time.perf_counter() - start, commit))
    log((out / "ratios.md").read_text())
    log(f"wrote {out}/results.csv, pareto.png, pareto.md, ratios.md, machine.md" + (", scaling.csv, scaling.png" if scaling_rows else ""))
    return rows


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

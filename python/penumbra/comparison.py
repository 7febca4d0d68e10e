"""Render methods and ground truth of the same scene (Mitsuba, or the
engine's ``raytraced`` at a high sample count), measure, time, and draw them:
``penumbra.compare(...)`` (one method, side by side), :func:`compare_methods`
and ``penumbra compare`` (every method, one picture).

Times are warm: one untimed warm-up render, then the median of ``repeats``
timed renders, each the wall clock of the whole render call (scene upload,
every pass, read-back). The warm-up's own time is kept as ``cold_ms`` (it
includes building pipelines and the driver's shader compilation). Renders
are timed without a pass cache, so every timed render runs every pass, and on
a software adapter (lavapipe) with CPU clocks around each pass, since its GPU
timestamps under-read (the README's "Timings")."""

from __future__ import annotations

import math
import os
import statistics
import textwrap
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable

import numpy as np

from penumbra import metrics as metrics_module
from penumbra.errors import InvalidInputError, ParameterError, SceneError
from penumbra.mitsuba import GroundTruth, ground_truth
from penumbra.render import Renderer, RenderResult, adapter_info, methods as implemented_methods
from penumbra.scene import Camera, Scene

__all__ = [
    "Comparison",
    "MethodComparison",
    "Timing",
    "compare",
    "compare_methods",
    "horizon_band",
    "comparison_figure",
    "methods_figure",
    "timed_render",
    "timing_renderer",
    "DEFAULT_SIZE",
    "PAPER",
    "DEFAULT_SPP",
    "DEFAULT_REPEATS",
    "DEFAULT_BUDGET_S",
]

#: Image side, ground-truth samples per pixel and timed renders of ``penumbra
#: compare``: the whole comparison of every method on the default scene takes
#: about a minute on 2 CPU cores with lavapipe (``reference``'s 256 shadow
#: maps are most of it), and at 1024 spp the ground truth's own noise is a
#: third of ``reference``'s error (docs/ground_truth.md has noise against spp).
DEFAULT_SIZE = 256
DEFAULT_SPP = 1024
DEFAULT_REPEATS = 5
#: Timed renders of one method stop early once they add up to this many
#: seconds (at least one is always timed): ``reference`` takes seconds a render.
DEFAULT_BUDGET_S = 5.0


@dataclass
class Timing:
    """Times of one method on one scene, in milliseconds: the wall clock of
    each whole render call. ``cold_ms`` is the first (warm-up) render,
    ``timed_ms`` the renders after it; ``warm_ms`` is their median.
    ``pass_clock`` is where the per-pass ``timings`` came from
    (``cpu_clock`` or ``gpu_timestamps``)."""

    cold_ms: float
    timed_ms: list[float]
    pass_clock: str

    @property
    def warm_ms(self) -> float:
        return float(statistics.median(self.timed_ms))

    def describe(self) -> str:
        """Which clock, and how the figure was taken."""
        passes = {"cpu_clock": "CPU clocks", "gpu_timestamps": "GPU timestamps"}.get(self.pass_clock, self.pass_clock)
        return f"wall clock of the render call, median of {len(self.timed_ms)} after a warm-up render; passes by {passes}"


#: The paper's values of the parameters whose defaults depart from it for
#: accuracy, by method: the faithful version that the tests and benchmarks
#: measure beside the defaults (docs/methods/pvmf.md, docs/methods/pcss.md,
#: docs/methods/pvm.md).
#: The repairs for real meshes (``repairs``, ``bias``, ``blur_min_width``)
#: keep their defaults here.
PAPER: dict[str, dict[str, Any]] = {
    "pvmf": {"kernel": "square", "n_blur": 12, "offsets": "unit", "umbra": "filter", "s_e": 0.5, "mask_size": "map", "occluder_distance": "nearest_volume", "map_samples": 0},
    # Fernando 2005: the plane test, uniform search taps, the mean blocker
    # depth, and the centre's test alone (no horizon repair).
    # Cournia 4.1.3 and 4.2: one edge per texel of a map-sized volume map,
    # read at the pixel's texel, and the 3k^2 - 2k^3 interpolant of the
    # disk fraction.
    "pvm": {"falloff": True, "edges": "one", "volume_map_size": "map", "lookup": "texel", "umbra_test": "none", "map_samples": 0},
    "pcss": {"blocker_test": "plane", "search": "uniform", "blocker_depth": "mean", "horizon": False},
}


def timing_renderer() -> Renderer:
    """A renderer for timing: no pass cache (every timed render runs every
    pass), CPU clocks around each pass on a software adapter (lavapipe's GPU
    timestamps under-read), GPU timestamps on hardware."""
    timing = "cpu" if adapter_info().get("is_software") else "auto"
    return Renderer(timing, pass_cache=False)


def _uncached_render(renderer: Renderer, scene: Scene, method: str, camera: Camera | None, params: dict[str, Any]) -> RenderResult:
    """One render that runs every pass: a renderer's pass cache is cleared first."""
    if renderer.pass_cache:
        renderer.clear_pass_cache()
    return renderer.render(scene, method, camera=camera, **params)


def timed_render(
    renderer: Renderer,
    scene: Scene,
    method: str,
    *,
    repeats: int = DEFAULT_REPEATS,
    budget_s: float | None = None,
    camera: Camera | None = None,
    **params: Any,
) -> tuple[RenderResult, Timing]:
    """Renders once untimed (the warm-up: its time is ``cold_ms``), then
    ``repeats`` times timed, or fewer once the timed renders add up to
    ``budget_s`` seconds (at least one); returns the last result and the
    :class:`Timing`. A renderer with a pass cache has it cleared before each
    render, so every render runs every pass."""
    if isinstance(repeats, bool) or not isinstance(repeats, int) or repeats < 1:
        raise ParameterError(f"repeats must be an integer of at least 1, got {repeats!r}")

    def once() -> RenderResult:
        return _uncached_render(renderer, scene, method, camera, params)

    result = once()
    cold = result.total_ms
    timed = []
    for _ in range(repeats):
        result = once()
        timed.append(result.total_ms)
        if budget_s is not None and sum(timed) >= 1e3 * budget_s:
            break
    return result, Timing(cold, timed, result.timing_source)


@dataclass
class Comparison:
    """One method against the ground truth: its render, the ground truth, every
    metric of :func:`penumbra.metrics.compare` and, when timed, its :class:`Timing`."""

    result: RenderResult
    ground_truth: GroundTruth
    metrics: dict[str, float]
    timing: Timing | None = None

    def save_figure(self, path: str | os.PathLike[str]) -> None:
        comparison_figure(self, path)


def _truth(
    truth: str, scene: Scene, camera: Camera | None, spp: int, seed: int, noise_seed: int | None,
    cache_dir: str | os.PathLike[str] | None, renderer: Renderer,
) -> GroundTruth:
    """The ground truth ``truth`` names: ``"mitsuba"`` (cached under
    ``cache_dir``) or ``"raytraced"`` (:func:`penumbra.truth.raytraced_truth`
    at ``spp`` light samples, not cached)."""
    from penumbra.truth import TRUTHS, raytraced_truth

    if truth not in TRUTHS:
        raise ParameterError(f"truth must be one of {list(TRUTHS)}, got {truth!r}")
    if truth == "raytraced":
        return raytraced_truth(scene, camera, n_samples=spp, seed=seed, noise_seed=noise_seed, renderer=renderer)
    return ground_truth(scene, camera, spp=spp, seed=seed, noise_seed=noise_seed, cache_dir=cache_dir)


#: A ``raytraced`` ground truth takes at least this many times the light
#: samples of the ``raytraced`` render it judges (its noise then a quarter of
#: the render's variance, half its RMSE), and seeds other than the render's.
RAYTRACED_TRUTH_FACTOR = 4


@dataclass
class _TruthPlan:
    """The ground truth's samples and seeds once made independent of the
    method compared (:func:`_independent_truth`); ``note`` says what changed,
    ``refused`` why the method cannot be judged by this truth."""

    spp: int
    seed: int
    noise_seed: int | None
    note: str | None = None
    refused: str | None = None


def _independent_truth(truth: str, raytraced_params: dict[str, Any] | None, spp: int, seed: int, noise_seed: int | None) -> _TruthPlan:
    """A ``raytraced`` truth judging a ``raytraced`` render (its parameters
    ``raytraced_params``; None when none is compared) must not be that render
    again: at least :data:`RAYTRACED_TRUTH_FACTOR` times its light samples
    (``spp`` raised to it when lower) and seeds other than its own (the next
    free ones when ``seed`` or ``noise_seed`` is its seed). When the samples
    needed exceed ``raytraced``'s most, the plan is refused with the reason."""
    if truth != "raytraced" or raytraced_params is None:
        return _TruthPlan(spp, seed, noise_seed)
    from penumbra.render import method_info

    info = method_info("raytraced")
    effective = {**info.defaults(), **raytraced_params}
    samples, own_seed = int(effective["n_samples"]), int(effective["seed"])
    most = int(next(p.maximum for p in info.params if p.name == "n_samples"))
    need = RAYTRACED_TRUTH_FACTOR * samples
    if need > most:
        return _TruthPlan(spp, seed, noise_seed, refused=(
            f"a raytraced ground truth judging raytraced at n_samples={samples} needs {RAYTRACED_TRUTH_FACTOR}x its samples, "
            f"{need}, beyond raytraced's {most}: lower n_samples to {most // RAYTRACED_TRUTH_FACTOR} or less, or use truth='mitsuba'"
        ))
    notes = []
    if spp < need:
        notes.append(f"{need} light samples ({RAYTRACED_TRUTH_FACTOR}x raytraced's n_samples={samples}) instead of the {spp} asked")
        spp = need
    if own_seed in (seed, noise_seed):
        taken = {own_seed}
        free = (k for k in range(seed, seed + 4) if k not in taken)
        new_seed = next(free)
        new_noise = None if noise_seed is None else next(k for k in free if k != new_seed)
        notes.append(f"seeds {new_seed}" + (f" and {new_noise}" if new_noise is not None else "") + f", not raytraced's seed {own_seed}")
        seed, noise_seed = new_seed, new_noise
    return _TruthPlan(spp, seed, noise_seed, note="raytraced ground truth at " + "; ".join(notes) if notes else None)


def compare(
    scene: Scene,
    method: str = "hard",
    *,
    camera: Camera | None = None,
    renderer: Renderer | None = None,
    spp: int = 256,
    seed: int = 0,
    noise_seed: int | None = 1,
    cache_dir: str | os.PathLike[str] | None = None,
    out: str | os.PathLike[str] | None = None,
    repeats: int = DEFAULT_REPEATS,
    truth: str = "mitsuba",
    **params: Any,
) -> Comparison:
    """Renders ``scene`` with ``method`` (and its ``params``) and the ground
    truth (radiance and visibility at ``spp`` samples per pixel; with
    ``noise_seed`` a second ground truth for the noise floor), computes every
    metric of :mod:`penumbra.metrics`, times the method (:func:`timed_render`:
    a warm-up, then the median of ``repeats``), and writes the side-by-side
    picture to ``out`` when given.

    ``truth``: ``"mitsuba"`` (the independent default, cached under
    ``cache_dir``) or ``"raytraced"``: the engine's own method ``raytraced`` at
    ``spp`` light samples (:func:`penumbra.truth.raytraced_truth`; give it
    thousands: 4096 for a noise floor near Mitsuba's at 1024), not cached.
    A raytraced truth judging method ``raytraced`` is never that render
    again: it takes at least :data:`RAYTRACED_TRUTH_FACTOR` (4) times the
    method's ``n_samples`` (``spp`` is raised to it) and seeds other than the
    method's ``seed``; beyond ``raytraced``'s most samples it is refused."""
    if not isinstance(scene, Scene):
        raise SceneError(f"expected a penumbra.Scene, got {type(scene).__name__}")
    plan = _independent_truth(truth, params if method == "raytraced" else None, spp, seed, noise_seed)
    if plan.refused:
        raise ParameterError(plan.refused)
    renderer = renderer or timing_renderer()
    result, timing = timed_render(renderer, scene, method, repeats=repeats, camera=camera, **params)
    gt = _truth(truth, scene, camera, plan.spp, plan.seed, plan.noise_seed, cache_dir, renderer)
    comparison = Comparison(result, gt, metrics_module.compare(result, gt), timing)
    if out is not None:
        comparison.save_figure(out)
    return comparison


def _srgb(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0, 1)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def comparison_figure(c: Comparison, path: str | os.PathLike[str]) -> None:
    """One PNG: the method's radiance, Mitsuba's, and the visibility error
    (method minus ground truth) colour-mapped with its scale, metrics beneath."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    r, g = c.result.radiance, c.ground_truth.radiance
    exposure = 1.0 / max(float(np.percentile(g, 99.5)), 1e-12)
    diff = c.result.visibility.astype(np.float64) - c.ground_truth.visibility
    limit = max(float(np.abs(diff).max()), 1e-3)
    h, w = r.shape[:2]
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.6 * h / w + 1.0), constrained_layout=True)
    params = ", ".join(f"{k}={v}" for k, v in c.result.params.items())
    axes[0].imshow(_srgb(r * exposure))
    ms = c.timing.warm_ms if c.timing else c.result.total_ms
    clock = f"median of {len(c.timing.timed_ms)} after a warm-up" if c.timing else "one render, cold"
    axes[0].set_title(f"penumbra: {c.result.method}\n{ms:.0f} ms ({clock})", fontsize=9)
    axes[1].imshow(_srgb(g * exposure))
    gt_seconds = sum(c.ground_truth.seconds.values())
    axes[1].set_title(f"Mitsuba 3 ({c.ground_truth.variant}, {c.ground_truth.spp} spp)\n{gt_seconds:.1f} s", fontsize=9)
    image = axes[2].imshow(diff, cmap="RdBu_r", vmin=-limit, vmax=limit)
    axes[2].set_title("visibility error (method - ground truth)\nred: too lit, blue: too dark", fontsize=9)
    fig.colorbar(image, ax=axes[2], shrink=0.8, label="visibility difference")
    for ax in axes:
        ax.set_xticks([])
        ax.set_yticks([])
    m = c.metrics
    text = (
        f"{params}\n"
        f"visibility RMSE {m['visibility_rmse']:.4f} (noise {m.get('noise_visibility_rmse', float('nan')):.4f}), "
        f"penumbra {m['visibility_rmse_penumbra']:.4f} (noise {m.get('noise_visibility_rmse_penumbra', float('nan')):.4f}), "
        f"max {m['visibility_max_error']:.3f}, FLIP {m['visibility_flip']:.4f}; "
        f"radiance RMSE {100 * m.get('radiance_rmse_rel', float('nan')):.2f}% of the lit mean"
    )
    fig.supxlabel(text, fontsize=8)
    fig.savefig(path, dpi=100)
    plt.close(fig)


# ---------------------------------------------------------------------------
# Every method at once: ``penumbra compare``.


def _params_per_method(names: list[str], params: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """``params`` split by method: each method gets those it declares (an
    unimplemented method gets them all, and refuses itself); a parameter no
    method declares is refused here, naming it."""
    from penumbra.render import method_info

    declared: dict[str, set[str] | None] = {}
    for name in names:
        try:
            declared[name] = set(method_info(name).defaults())
        except ParameterError:
            declared[name] = None
    unused = [k for k in params if not any(d is None or k in d for d in declared.values())]
    if unused:
        raise ParameterError(f"unknown parameter(s) {unused}: declared by none of the methods compared ({names}); see penumbra.method_info")
    return {name: {k: v for k, v in params.items() if d is None or k in d} for name, d in declared.items()}


def _default_order() -> list[str]:
    """Implemented methods, ``reference`` (the in-engine yardstick) last."""
    names = implemented_methods()
    return [m for m in names if m != "reference"] + [m for m in names if m == "reference"]


@dataclass
class MethodComparison:
    """Several methods against one ground truth, each timed in the same run.

    ``rows`` holds a :class:`Comparison` per method that rendered (in the
    order asked), ``skipped`` the reason for each method that refused the
    scene or its parameters (an open mesh for ``pvm``, say), ``baseline`` the
    :class:`Timing` of ``hard`` on the same scene, which every time ratio
    divides by."""

    scene: Scene
    ground_truth: GroundTruth
    rows: list[Comparison]
    baseline: Timing
    params: dict[str, Any] = field(default_factory=dict)
    skipped: dict[str, str] = field(default_factory=dict)
    adapter: dict[str, Any] = field(default_factory=dict)
    repeats: int = DEFAULT_REPEATS
    budget_s: float | None = DEFAULT_BUDGET_S
    #: What the comparison changed from what was asked, in words (a raytraced
    #: truth raised to 4x the raytraced row's samples, or given other seeds).
    notes: list[str] = field(default_factory=list)

    def time_over_hard(self, row: Comparison) -> float:
        assert row.timing is not None
        return row.timing.warm_ms / self.baseline.warm_ms

    @property
    def clock(self) -> str:
        """Which clock, and how the times were taken."""
        passes = {"cpu_clock": "CPU clocks", "gpu_timestamps": "GPU timestamps"}.get(self.baseline.pass_clock, self.baseline.pass_clock)
        fewer = f" (fewer once they add up to {self.budget_s:g} s)" if self.budget_s is not None else ""
        return (f"wall clock of each render call, median of {self.repeats} after a warm-up render{fewer}, "
                f"taken in rounds of one render per method; passes by {passes}")

    def table(self) -> str:
        """The figures of the picture as a markdown table: a row per method
        compared, a row per method skipped with its reason, the ground
        truth's noise in the last row."""
        head = (
            "| method | penumbra RMSE | cast shadows | vis. RMSE | max error | FLIP | radiance RMSE (rel.) | warm ms | timed | time / hard | first render ms |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|"
        )
        lines = [head]
        for row in self.rows:
            m, t = row.metrics, row.timing
            assert t is not None
            lines.append(
                f"| {row.result.method} | {m['visibility_rmse_penumbra']:.4f} | {m.get('visibility_rmse_penumbra_cast', math.nan):.4f} | {m['visibility_rmse']:.4f} | "
                f"{m['visibility_max_error']:.3f} | {m['visibility_flip']:.4f} | {m['radiance_rmse_rel']:.4f} | "
                f"{t.warm_ms:.1f} | {len(t.timed_ms)} | {self.time_over_hard(row):.2f} | {t.cold_ms:.0f} |"
            )
        for method, reason in self.skipped.items():
            cell = " ".join(reason.split()).replace("|", "\\|")
            lines.append(f"| {method} | skipped: {cell} |" + " |" * 9)
        if self.rows and "noise_visibility_rmse" in self.rows[0].metrics:
            m = self.rows[0].metrics
            lines.append(
                f"| *ground-truth noise* | {m['noise_visibility_rmse_penumbra']:.4f} | {m.get('noise_visibility_rmse_penumbra_cast', math.nan):.4f} | {m['noise_visibility_rmse']:.4f} | "
                f"{m['noise_visibility_max_error']:.3f} | {m['noise_visibility_flip']:.4f} | {m['noise_radiance_rmse_rel']:.4f} | | | | |"
            )
        return "\n".join(lines)

    def to_json(self) -> dict[str, Any]:
        gt = self.ground_truth
        camera = self.scene.camera
        return {
            "scene": self.scene.name,
            "size": [camera.width, camera.height] if camera else None,
            "params": self.params,
            "adapter": self.adapter,
            "clock": self.clock,
            "hard_warm_ms": self.baseline.warm_ms,
            "ground_truth": {
                "variant": gt.variant,
                "spp": gt.spp,
                "seconds": gt.seconds,
                "cached": gt.cached,
                "noise_seconds": gt.second.seconds if gt.second else None,
            },
            "methods": [
                {
                    "method": row.result.method,
                    "params": row.result.params,
                    "metrics": row.metrics,
                    "warm_ms": row.timing.warm_ms if row.timing else None,
                    "timed_ms": row.timing.timed_ms if row.timing else None,
                    "cold_ms": row.timing.cold_ms if row.timing else None,
                    "time_over_hard": self.time_over_hard(row),
                    "pass_ms": row.result.timings,
                    "pass_clock": row.result.timing_source,
                }
                for row in self.rows
            ],
            "skipped": self.skipped,
            "notes": self.notes,
        }

    def save_figure(self, path: str | os.PathLike[str]) -> None:
        methods_figure(self, path)


def compare_methods(
    scene: Scene,
    methods: Iterable[str] | None = None,
    *,
    params: dict[str, Any] | None = None,
    camera: Camera | None = None,
    renderer: Renderer | None = None,
    spp: int = DEFAULT_SPP,
    seed: int = 0,
    noise_seed: int | None = 1,
    repeats: int = DEFAULT_REPEATS,
    budget_s: float | None = DEFAULT_BUDGET_S,
    cache_dir: str | os.PathLike[str] | None = None,
    out: str | os.PathLike[str] | None = None,
    progress: Callable[[str], None] | None = None,
    truth: str = "mitsuba",
) -> MethodComparison:
    """Every method in ``methods`` (default: every implemented one,
    ``reference`` last) against Mitsuba ground truth of ``scene``, each timed
    with :func:`timed_render` (``repeats``, ``budget_s``) in this one run, ``hard`` too (the time ratios'
    baseline) when it is not among them. ``params`` go to every method that
    declares them (``map_size`` to the shadow-mapped ones, not to
    ``raytraced``); one that no method compared declares is a
    :class:`~penumbra.errors.ParameterError`.

    With ``truth="raytraced"`` and method ``raytraced`` among those compared,
    the truth takes at least 4x the raytraced row's ``n_samples`` (``spp``
    raised to it) and seeds other than the row's, said in ``notes``; when
    that is more than ``raytraced`` takes, the row is left out with the
    reason in ``skipped`` (raised when it is the only method).

    When more than one method is asked, a method that refuses the scene or the
    parameters (a :class:`~penumbra.errors.InvalidInputError`) is skipped
    with its reason in ``skipped``; a single method's refusal, or every
    method's, is raised. ``progress`` receives a line per step. With ``out``
    the picture (:func:`methods_figure`) is written there."""
    if not isinstance(scene, Scene):
        raise SceneError(f"expected a penumbra.Scene, got {type(scene).__name__}")
    names = _default_order() if methods is None else list(methods)
    if not names:
        raise ParameterError("no method to compare")
    known = implemented_methods(implemented_only=False)
    for name in names:
        if not isinstance(name, str) or name not in known:
            raise ParameterError(f"unknown method {name!r}; methods: {implemented_methods()}")
    if isinstance(repeats, bool) or not isinstance(repeats, int) or repeats < 1:
        raise ParameterError(f"repeats must be an integer of at least 1, got {repeats!r}")
    params = dict(params or {})
    own = _params_per_method(names, params)
    say = progress or (lambda line: None)
    # A raytraced truth is not the raytraced row again (RAYTRACED_TRUTH_FACTOR).
    plan = _independent_truth(truth, own.get("raytraced") if "raytraced" in names else None, spp, seed, noise_seed)
    left_out: dict[str, str] = {}
    if plan.refused:
        if names == ["raytraced"]:
            raise ParameterError(plan.refused)
        left_out["raytraced"] = plan.refused
        names = [n for n in names if n != "raytraced"]
        say(f"raytraced: left out: {plan.refused}")
        plan = _TruthPlan(spp, seed, noise_seed)
    if plan.note:
        say(plan.note)
    renderer = renderer or timing_renderer()
    camera = camera or scene.camera

    # Renders first: a parameter a method refuses shows in seconds, before
    # the ground truth's first (uncached) render. Each method's warm-up
    # render, then the timed renders in rounds, one of each method per round:
    # a shared machine's load, which drifts over seconds, then weighs on every
    # method alike instead of on whichever ran during a busy spell.
    timed_names = names if "hard" in names else [*names, "hard"]
    warm: dict[str, RenderResult] = {}
    cold: dict[str, float] = {}
    skipped: dict[str, str] = dict(left_out)
    errors: list[InvalidInputError] = []
    for i, name in enumerate(timed_names, 1):
        role = "" if name in names else ", the time baseline, with its defaults"
        say(f"{name} ({i}/{len(timed_names)}{role}): warm-up render")
        try:
            warm[name] = _uncached_render(renderer, scene, name, camera, own[name] if name in names else {})
        except InvalidInputError as e:
            if len(names) == 1:
                raise
            if name == "hard" and name in names:
                # Refused the parameters: still timed as the baseline, with its defaults.
                timed_names.append("hard")
                names = [n for n in names if n != "hard"]
            skipped[name] = str(e)
            errors.append(e)
            say(f"{name}: skipped: {e}")
            continue
        cold[name] = warm[name].total_ms
    if not any(name in warm for name in names):
        raise errors[0]
    if "hard" not in warm:
        raise errors[-1]
    timed: dict[str, list[float]] = {name: [] for name in warm}
    last: dict[str, RenderResult] = dict(warm)
    for round_ in range(1, repeats + 1):
        active = [n for n in warm if budget_s is None or not timed[n] or sum(timed[n]) < 1e3 * budget_s]
        if not active:
            break
        say(f"timed round {round_}/{repeats}: {', '.join(active)}")
        for name in active:
            last[name] = _uncached_render(renderer, scene, name, camera, own[name] if name in names else {})
            timed[name].append(last[name].total_ms)
    timings = {name: Timing(cold[name], timed[name], last[name].timing_source) for name in warm}
    for name in warm:
        say(f"{name}: {timings[name].warm_ms:.1f} ms warm (median of {len(timed[name])}), {cold[name]:.0f} ms first")
    rendered = [(last[name], timings[name]) for name in names if name in warm]
    baseline = timings["hard"]

    started = time.perf_counter()
    say(f"ground truth: {truth}, {plan.spp} spp, two seeds" + (" (cached after the first run)" if truth == "mitsuba" else ""))
    gt = _truth(truth, scene, camera, plan.spp, plan.seed, plan.noise_seed, cache_dir, renderer)
    cached = all(gt.cached.values()) and (gt.second is None or all(gt.second.cached.values()))
    say(f"ground truth: {gt.variant}, {'read from the cache' if cached else 'rendered'} in {time.perf_counter() - started:.1f} s")
    rows = [Comparison(result, gt, _with_cast_shadows(metrics_module.compare(result, gt), result, gt, scene), timing)
            for result, timing in rendered]
    info = renderer.adapter_info
    comparison = MethodComparison(scene, gt, rows, baseline, params, skipped, dict(info), repeats, budget_s, [plan.note] if plan.note else [])
    if out is not None:
        say(f"drawing {os.fspath(out)}")
        comparison.save_figure(out)
    return comparison


def horizon_band(result: RenderResult, scene: Scene) -> np.ndarray:
    """Pixels whose surface has the light sphere cut by its own horizon
    (``|n . (c - p)| < r``): a smooth caster's terminator, where the true
    visibility fades because part of the light sets below the surface, not
    because something occludes it. Shadow-map methods are hard there (a
    surface facing away from the light's centre gets visibility 0)."""
    to_light = np.asarray(scene.light.center, dtype=np.float64) - result.position.astype(np.float64)
    band = np.abs((result.normal.astype(np.float64) * to_light).sum(axis=-1)) < float(scene.light.radius)
    return band & (result.object_id >= 0)


def _with_cast_shadows(m: dict[str, float], result: RenderResult, gt: GroundTruth, scene: Scene) -> dict[str, float]:
    """Adds ``visibility_rmse_penumbra_cast``: the penumbra RMSE over the
    penumbra less the :func:`horizon_band`, i.e. over the shadows cast by
    occluders (with its noise when the ground truth has a second seed)."""
    cast = metrics_module.penumbra_region(gt.visibility) & ~horizon_band(result, scene)
    m = dict(m)
    m["visibility_rmse_penumbra_cast"] = metrics_module.rmse(result.visibility, gt.visibility, cast)
    if gt.second is not None:
        m["noise_visibility_rmse_penumbra_cast"] = metrics_module.rmse(gt.visibility, gt.second.visibility, cast) / math.sqrt(2)
    return m


def _short_params(params: dict[str, Any]) -> str:
    return ", ".join(f"{k}={v}" for k, v in params.items()) or "defaults"


#: The error colour scale of :func:`methods_figure`: +-0.25 of visibility,
#: larger errors clipped (the colour bar's arrows), so that the soft methods'
#: errors show beside ``hard``'s.
ERROR_SCALE = 0.25


def _crop(truth: np.ndarray, diffs: list[np.ndarray], pad: float = 0.12) -> tuple[slice, slice]:
    """The square part of the image around the penumbrae and the errors (the
    rest is fully lit, fully shadowed or background), padded by ``pad``."""
    h, w = truth.shape
    interest = metrics_module.penumbra_region(truth)
    for d in diffs:
        interest |= np.abs(d) > 0.02
    if not interest.any():
        return slice(0, h), slice(0, w)
    ys, xs = np.nonzero(interest)
    y0, y1, x0, x1 = ys.min(), ys.max() + 1, xs.min(), xs.max() + 1
    side = int(max(y1 - y0, x1 - x0) * (1 + 2 * pad))
    side = min(max(side, 16), h, w)
    cy, cx = (y0 + y1) // 2, (x0 + x1) // 2
    top = int(np.clip(cy - side // 2, 0, h - side))
    left = int(np.clip(cx - side // 2, 0, w - side))
    return slice(top, top + side), slice(left, left + side)


def methods_figure(c: MethodComparison, path: str | os.PathLike[str]) -> None:
    """One PNG: a row per method (its visibility; its error against the
    ground truth's visibility, every row on one colour scale, ±``ERROR_SCALE``;
    its penumbra RMSE and warm time as a ratio to ``hard``'s), a row for the
    ground truth (its visibility and its noise: one seed minus the other, on
    the same scale), and a time-against-error scatter of the methods. The
    images are cropped to the part of the frame with penumbrae or errors."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.gridspec import GridSpec

    gt = c.ground_truth
    truth = gt.visibility.astype(np.float64)
    diffs = [row.result.visibility.astype(np.float64) - truth for row in c.rows]
    noise = gt.second.visibility.astype(np.float64) - truth if gt.second is not None else None
    rows_y, cols_x = _crop(truth, diffs)
    limit = ERROR_SCALE
    n = len(c.rows) + 1
    slots = max(n, 5)  # room for the scatter and the notes beside few rows
    cell, top_in, bottom_in = 1.45, 0.75, 0.75
    height = slots * cell + top_in + bottom_in
    fig = plt.figure(figsize=(2 * cell + 1.75 + 4.3, height))
    outer = GridSpec(1, 2, figure=fig, width_ratios=[2 * cell + 1.75, 4.0], wspace=0.16,
                     left=0.045, right=0.985, top=1 - top_in / height, bottom=bottom_in / height)
    grid = outer[0].subgridspec(slots, 3, width_ratios=[1, 1, 1.3], wspace=0.06, hspace=0.08)
    span = max(2, min(slots - 1, (slots * 3 + 4) // 5))
    side = outer[1].subgridspec(2, 1, height_ratios=[span, slots - span], hspace=0.25)

    background = c.rows[0].result.object_id < 0

    def image(ax: Any, data: np.ndarray, cmap: str, **kw: Any) -> Any:
        colours = matplotlib.colormaps[cmap].with_extremes(bad="#b9c7d6")
        masked = np.ma.masked_where(background, data)[rows_y, cols_x]
        shown = ax.imshow(masked, interpolation="nearest", cmap=colours, **kw)
        ax.set_xticks([])
        ax.set_yticks([])
        return shown

    def label(ax: Any, text: str) -> None:
        ax.axis("off")
        ax.text(0.05, 0.5, text, fontsize=8.5, va="center", ha="left", transform=ax.transAxes, linespacing=1.35)

    error_image = None
    noise_pen = c.rows[0].metrics.get("noise_visibility_rmse_penumbra", float("nan"))
    for i, row in enumerate(c.rows):
        ax_v, ax_e, ax_t = (fig.add_subplot(grid[i, j]) for j in range(3))
        image(ax_v, row.result.visibility, cmap="gray", vmin=0, vmax=1)
        error_image = image(ax_e, diffs[i], cmap="RdBu_r", vmin=-limit, vmax=limit)
        ax_v.set_ylabel(row.result.method, fontsize=11, fontweight="bold")
        m, t = row.metrics, row.timing
        warm = f"{t.warm_ms:.0f} ms warm" if t else ""
        ratio = c.time_over_hard(row)
        cast = m.get("visibility_rmse_penumbra_cast", math.nan)
        label(ax_t, f"penumbra RMSE {m['visibility_rmse_penumbra']:.3f}\n  cast shadows {cast:.3f}\n"
                    f"{ratio:.{2 if ratio < 10 else 0}f} x hard's time\n({warm})")
        if i == 0:
            ax_v.set_title("visibility", fontsize=9)
            ax_e.set_title("method - ground truth", fontsize=9)
    ax_v, ax_e, ax_t = (fig.add_subplot(grid[n - 1, j]) for j in range(3))
    image(ax_v, truth, cmap="gray", vmin=0, vmax=1)
    ax_v.set_ylabel("Mitsuba", fontsize=11, fontweight="bold")
    if noise is not None:
        image(ax_e, noise, cmap="RdBu_r", vmin=-limit, vmax=limit)
    else:
        ax_e.axis("off")
    gt_s = sum(gt.seconds.values()) + (sum(gt.second.seconds.values()) if gt.second else 0.0)
    cached = all(gt.cached.values())
    label(ax_t, f"ground truth, {gt.spp} spp\nits noise (seed 1 - seed 0):\npenumbra RMSE {noise_pen:.4f}\n"
                f"{gt_s:.0f} s{' (cached)' if cached else ''}, {gt.variant}")
    assert error_image is not None
    pos = ax_e.get_position()
    bar = fig.add_axes((pos.x0 - pos.width * 0.5, pos.y0 - 0.3 / height, pos.width * 2, 0.09 / height))
    fig.colorbar(error_image, cax=bar, orientation="horizontal", extend="both", ticks=[-limit, -limit / 2, 0, limit / 2, limit])
    bar.tick_params(labelsize=7)
    bar.set_xlabel("visibility error: red too lit, blue too dark", fontsize=7, labelpad=1)

    ax_s = fig.add_subplot(side[0])
    xs = [c.time_over_hard(row) for row in c.rows]
    ys = [row.metrics["visibility_rmse_penumbra"] for row in c.rows]
    ax_s.scatter(xs, ys, s=24, color="tab:blue", zorder=3, label="penumbra")
    casts = [row.metrics.get("visibility_rmse_penumbra_cast", math.nan) for row in c.rows]
    ax_s.scatter(xs, casts, s=24, facecolors="none", edgecolors="tab:orange", zorder=3, label="cast shadows")
    ax_s.legend(fontsize=7, loc="upper right", title="penumbra RMSE", title_fontsize=7)
    right = max(xs)
    placed: list[tuple[float, float]] = []
    for x, y, row in sorted(zip(xs, ys, c.rows), key=lambda p: (p[0], p[1])):
        at_right = x == right and len(xs) > 1
        # A label near one already placed above its point goes below its own.
        crowded = any(abs(math.log10(x / px)) < 0.25 and abs(math.log10(y / py)) < 0.08 for px, py in placed)
        placed.append((x, y))
        ax_s.annotate(row.result.method, (x, y), textcoords="offset points", xytext=(-5 if at_right else 5, -11 if crowded else 4),
                      ha="right" if at_right else "left", fontsize=8)
    if math.isfinite(noise_pen) and noise_pen > 0:
        ax_s.axhline(noise_pen, color="0.5", linestyle="--", linewidth=0.8)
        ax_s.annotate("ground truth's noise", (min(xs), noise_pen), textcoords="offset points", xytext=(0, 3), fontsize=7, color="0.35")
    ax_s.set_xscale("log")
    ax_s.set_yscale("log")
    ax_s.margins(x=0.12, y=0.12)
    ax_s.set_xlabel("warm time / hard's (log)", fontsize=8)
    ax_s.set_ylabel("visibility RMSE (log)", fontsize=8)
    ax_s.set_title("time against error (lower left is better)", fontsize=9)
    ax_s.tick_params(which="both", labelsize=7)
    from matplotlib.ticker import FormatStrFormatter

    for axis in (ax_s.xaxis, ax_s.yaxis):
        axis.set_major_formatter(FormatStrFormatter("%g"))
        axis.set_minor_formatter(FormatStrFormatter(""))
    ax_s.grid(True, which="both", linewidth=0.3, alpha=0.5)

    camera = c.scene.camera
    size = f", {camera.width}x{camera.height}" if camera else ""
    given = f"params {_short_params(c.params)}" if c.params else "each method's defaults"
    fig.text(0.045, 1 - 0.12 / height, f"penumbra compare: {c.scene.name}{size}, {given}, against Mitsuba 3 ground truth",
             fontsize=11, ha="left", va="top")
    software = ", software" if c.adapter.get("is_software") else ""
    crop = f"rows {rows_y.start}-{rows_y.stop}, columns {cols_x.start}-{cols_x.stop}"
    notes = [
        f"Times: {c.clock}. hard: {c.baseline.warm_ms:.0f} ms on {c.adapter.get('name', 'this adapter')}{software}.",
        "Penumbra RMSE: the visibility error over the pixels whose true visibility is in (0.02, 0.98); "
        "cast shadows: the same less the pixels whose surface has the light cut by its horizon (the sphere's terminator).",
        f"Images cropped to the shadows ({crop}); errors clipped at +-{limit:g}.",
        "`penumbra compare` prints every figure as a table.",
    ]
    notes += c.notes
    if c.skipped:
        notes += [f"Skipped {k}: {v if len(v) < 150 else v[:147] + '...'}" for k, v in c.skipped.items()]
    ax_n = fig.add_subplot(side[1])
    ax_n.axis("off")
    ax_n.text(0.0, 1.0, "\n".join(textwrap.fill(line, 70) for line in notes), fontsize=7.5, ha="left", va="top",
              transform=ax_n.transAxes, linespacing=1.4)
    fig.savefig(path, dpi=100)
    plt.close(fig)

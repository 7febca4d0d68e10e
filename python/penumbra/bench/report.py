"""``penumbra bench`` reports: Pareto fronts, equal-error ratios, the
markdown tables, the plots and the CSV files."""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np

__all__ = [
    "ERROR",
    "Point",
    "aggregate",
    "pareto_front",
    "time_at_error",
    "pareto_table",
    "ratio_tables",
    "plot_pareto",
    "plot_scaling",
    "write_csv",
    "suite_tables",
    "what_to_use",
    "markdown_table",
    "read_csv",
    "time_to_error_tables",
    "cost_tables",
    "halves_tables",
    "BUDGETS",
]

#: The metric the Pareto plot, the tables and the ratios use.
ERROR = "visibility_rmse_penumbra"


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


def write_csv(path: Path, rows: list[dict[str, Any]]) -> None:
    columns: list[str] = []
    for row in rows:
        columns += [k for k in row if k not in columns]
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=columns)
        writer.writeheader()
        writer.writerows(rows)


def read_csv(path: Path) -> list[dict[str, Any]]:
    """A ``results.csv`` read back as :func:`write_csv` wrote it: numbers as
    floats, empty cells dropped (a column the row did not have)."""

    def value(text: str) -> Any:
        try:
            return float(text)
        except ValueError:
            return text

    with open(path, newline="") as f:
        return [{k: value(v) for k, v in row.items() if v != ""} for row in csv.DictReader(f)]


@dataclass
class Point:
    """One configuration averaged over the scenes."""

    method: str
    label: str
    kind: str
    ms: float
    time_over_hard: float
    error: float


def _median(values: list[float]) -> float:
    """The median of the finite values; NaN when there is none (the penumbra
    RMSE of a scene without a penumbra, such as a light of radius 0)."""
    finite = [v for v in values if math.isfinite(v)]
    return float(np.median(finite)) if finite else math.nan


def aggregate(rows: list[dict[str, Any]]) -> list[Point]:
    """Medians over the scenes of each (method, setting): time, time over
    ``hard`` and penumbra visibility RMSE (a scene where a method fails does
    not move the median as it moves a mean; a scene without a penumbra has
    no penumbra RMSE and is left out of its median)."""
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for row in rows:
        groups.setdefault((row["method"], row["label"]), []).append(row)
    return [
        Point(method, lab, g[0]["kind"], _median([float(r["total_ms"]) for r in g]),
              _median([float(r["time_over_hard"]) for r in g]), _median([float(r[ERROR]) for r in g]))
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
        "Medians over the scenes. Best setting: the lowest penumbra visibility RMSE. The peers' times at that error are",
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
    each method's Pareto front as a line, peers dashed; settings without a
    finite positive error (no scene with a penumbra) are left out."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5.5))
    for method, group in _by_method(points).items():
        # Log axes: a point without a finite positive time and error (no penumbra anywhere) is not drawn.
        xy = [(p.ms, p.error) for p in group if p.ms > 0 and p.error > 0 and math.isfinite(p.ms) and math.isfinite(p.error)]
        if not xy:
            continue
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


#: The penumbra RMSE budgets of :func:`what_to_use`.
BUDGETS = (0.02, 0.03, 0.05, 0.08, 0.12, 0.2)


def _groups(rows: list[dict[str, Any]]) -> dict[tuple[str, str, str], list[dict[str, Any]]]:
    groups: dict[tuple[str, str, str], list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault((r.get("size", ""), r["method"], r["label"]), []).append(r)
    return groups


def _median_ratio(group: list[dict[str, Any]]) -> str:
    values = [float(r["time_over_mitsuba"]) for r in group if r.get("time_over_mitsuba") not in (None, "") and math.isfinite(float(r["time_over_mitsuba"]))]
    if not values:
        return "n/a"
    bounded = sum(r.get("mitsuba_bound", "=") != "=" for r in group)
    return f"{float(np.median(values)):.3g}" + (f" ({bounded} bounds)" if bounded else "")


def suite_tables(rows: list[dict[str, Any]]) -> str:
    """Per size, one line per method and setting: over the scenes, the median
    and worst penumbra RMSE, stray pixels, time over ``hard`` and time over
    Mitsuba's at equal error (rows carry ``time_over_mitsuba``)."""
    out = []
    by_size: dict[str, list[tuple[str, str, list[dict[str, Any]]]]] = {}
    for (size, method, lab), group in _groups(rows).items():
        by_size.setdefault(size, []).append((method, lab, group))
    for size, entries in by_size.items():
        n = len({r["scene"] for _, _, g in entries for r in g})
        out += [f"### {size}, {n} scenes", "",
                "| method | setting | penumbra RMSE median | worst | scenes at most 0.5x `hard`'s | stray % median | worst | scenes over 0.5% stray "
                "| time / hard median | worst | time / Mitsuba at equal error, median |",
                "|---|---|---|---|---|---|---|---|---|---|---|"]
        hard = {r["scene"]: float(r[ERROR]) for m, lab, g in entries if (m, lab) == ("hard", "default") for r in g}
        for method, lab, g in entries:
            err = [float(r[ERROR]) for r in g]
            half = sum(float(r[ERROR]) <= 0.5 * hard[r["scene"]] for r in g if r["scene"] in hard)
            stray = [100 * float(r.get("stray_fraction") or 0.0) for r in g]
            over = [float(r["time_over_hard"]) for r in g]
            out.append(f"| {method} | {lab} | {np.median(err):.4f} | {max(err):.4f} | {half} of {len(g)} | {np.median(stray):.2f} | {max(stray):.2f} | "
                       f"{sum(x > 0.5 for x in stray)} | {np.median(over):.2f} | {max(over):.2f} | {'-' if method == 'mitsuba' else _median_ratio(g)} |")
        out.append("")
    return "\n".join(out)


def halves_tables(rows: list[dict[str, Any]]) -> str:
    """Where each method's penumbra error lies (``metrics.penumbra_halves``):
    per size, one line per method and setting, over the scenes, the median
    RMSE over the inner half of the penumbra (ground truth under 1/2, mostly
    where the light's centre is hidden) and over the outer half, the median
    share of the squared penumbra error that lies in the inner half, and on
    how many scenes that share is over one half. Rows without the halves
    (results of a run before them) are left out; "" where none has them."""
    out: list[str] = []
    by_size: dict[str, list[tuple[str, str, list[dict[str, Any]]]]] = {}
    for (size, method, lab), group in _groups(rows).items():
        g = [r for r in group if all(math.isfinite(_number(r, k)) for k in ("visibility_rmse_inner", "visibility_rmse_outer", "penumbra_inner_pixels", "penumbra_pixels"))]
        if g:
            by_size.setdefault(size, []).append((method, lab, g))
    for size, entries in by_size.items():
        out += [f"### {size}", "",
                "| method | setting | scenes | inner RMSE median | outer RMSE median | inner share of the squared error, median | scenes where the inner half holds most |",
                "|---|---|---|---|---|---|---|"]
        for method, lab, g in entries:
            inner = [_number(r, "visibility_rmse_inner") for r in g]
            outer = [_number(r, "visibility_rmse_outer") for r in g]
            shares = []
            for r, i, o in zip(g, inner, outer):
                n_in = _number(r, "penumbra_inner_pixels")
                n_out = _number(r, "penumbra_pixels") - n_in
                total = n_in * i * i + n_out * o * o
                shares.append(n_in * i * i / total if total > 0 else 0.0)
            out.append(f"| {method} | {lab} | {len(g)} | {np.median(inner):.4f} | {np.median(outer):.4f} | {np.median(shares):.2f} | {sum(x > 0.5 for x in shares)} of {len(g)} |")
        out.append("")
    return "\n".join(out)


#: Passes every shadow-map method shares, and the ones after the method's
#: own: what `cost_tables` leaves out of "the method's own passes".
SHARED_PASSES = ("ms_gbuffer", "ms_shadow_map", "ms_shading", "ms_readback", "ms_radiance")


def _number(row: dict[str, Any], key: str) -> float:
    value = row.get(key)
    try:
        return float(value) if value not in (None, "") else math.nan
    except (TypeError, ValueError):
        return math.nan


def cost_tables(rows: list[dict[str, Any]]) -> str:
    """Whether each method's cost follows the penumbra (issue 30): per size
    and setting, over the scenes, the median time of the shadow map and of
    the method's own passes (the sum of its passes' times but the G-buffer,
    the shadow map, shading and readback), that per 1000 penumbra pixels, and the exponents of a
    least-squares fit of log(own ms) = c + a log(penumbra pixels) + b
    log(triangles) with its R^2: a near 1 and b near 0 say the work follows
    the penumbra on screen, not the mesh. The costliest own pass and its
    median close each row. Settings with fewer than 5 scenes that have a
    penumbra and a triangle count get no fit."""
    out: list[str] = []
    by_size: dict[str, list[tuple[str, str, list[dict[str, Any]]]]] = {}
    for (size, method, lab), group in _groups(rows).items():
        if method != "mitsuba":
            by_size.setdefault(size, []).append((method, lab, group))
    for size, entries in by_size.items():
        out += [f"### {size}", "",
                "| method | setting | scenes | shadow map ms | own passes ms | own ms per 1000 penumbra px "
                "| exponent on penumbra px | exponent on triangles | R^2 | costliest own pass (median ms) |",
                "|---|---|---|---|---|---|---|---|---|---|"]
        for method, lab, group in entries:
            own, px, tris, shadow = [], [], [], []
            passes: dict[str, list[float]] = {}
            for r in group:
                mine = [_number(r, k) for k in r if k.startswith("ms_") and k not in SHARED_PASSES]
                own.append(max(sum(v for v in mine if math.isfinite(v)), 1e-3))
                px.append(_number(r, "penumbra_pixels"))
                tris.append(_number(r, "stat_triangles"))
                shadow.append(_number(r, "ms_shadow_map"))
                for k, v in r.items():
                    if k.startswith("ms_") and k not in SHARED_PASSES and math.isfinite(_number(r, k)):
                        passes.setdefault(k[3:], []).append(float(v))
            fit_rows = [(o, p, t) for o, p, t in zip(own, px, tris) if p > 0 and t > 0 and math.isfinite(o)]
            per_k = [1000 * o / p for o, p, _ in fit_rows]
            a = b = r2 = "-"
            if len(fit_rows) >= 5:
                y = np.log([o for o, _, _ in fit_rows])
                x = np.column_stack([np.ones(len(fit_rows)), np.log([p for _, p, _ in fit_rows]), np.log([t for _, _, t in fit_rows])])
                coef, *_ = np.linalg.lstsq(x, y, rcond=None)
                spread = float(np.sum((y - y.mean()) ** 2))
                r2_value = 1.0 - float(np.sum((y - x @ coef) ** 2)) / spread if spread > 0 else 1.0
                a, b, r2 = f"{coef[1]:.2f}", f"{coef[2]:.2f}", f"{r2_value:.2f}"
            costliest = max(passes.items(), key=lambda kv: float(np.median(kv[1])), default=None)
            worst = f"{costliest[0]} ({np.median(costliest[1]):.1f})" if costliest else "-"
            out.append(f"| {method} | {lab} | {len(group)} | {_median(shadow):.1f} | {_median(own):.1f} | "
                       f"{_median(per_k):.2f} | {a} | {b} | {r2} | {worst} |")
        out.append("")
    return "\n".join(out)


def what_to_use(rows: list[dict[str, Any]], budgets: Sequence[float] = BUDGETS) -> str:
    """For each size and penumbra RMSE budget: the fastest setting (least
    median time over the scenes) whose median error meets the budget, and the
    fastest whose worst error does, beside the median time Mitsuba's
    visibility estimator needs for that error on the same scenes."""
    out = ["### What to use", "",
           "Fastest setting (least median time over the scenes) whose median penumbra RMSE meets the budget, and whose worst does; "
           "Mitsuba: the median over the scenes of the time its visibility estimator needs for that RMSE, interpolated on each scene's curve.", ""]
    by_size: dict[str, dict[tuple[str, str], list[dict[str, Any]]]] = {}
    for (size, method, lab), group in _groups(rows).items():
        by_size.setdefault(size, {})[(method, lab)] = group
    for size, groups in by_size.items():
        out += [f"{size}:", "", "| budget | fastest at the median | median ms | fastest in the worst case | median ms | Mitsuba median ms |", "|---|---|---|---|---|---|"]
        scenes_ = dict.fromkeys(r["scene"] for g in groups.values() for r in g)
        curves = {s: [(float(r["total_ms"]), float(r[ERROR])) for g in groups.values() for r in g if r["scene"] == s and r["method"] == "mitsuba"] for s in scenes_}
        for budget in budgets:
            cells = []
            for use in (np.median, max):
                fits = [(float(np.median([float(r["total_ms"]) for r in g])), m, lab) for (m, lab), g in groups.items()
                        if m != "mitsuba" and len(g) == len(scenes_) and use([float(r[ERROR]) for r in g]) <= budget]
                cells += [f"{min(fits)[1]} {min(fits)[2]}", f"{min(fits)[0]:.1f}"] if fits else ["none", "-"]
            times = [time_at_error(c, budget) for c in curves.values() if c]
            reached = [t for t, bound in times if bound != ">="]
            mitsuba = f"{np.median([t for t, _ in times]):.1f}" + ("" if len(reached) == len(times) else f" ({len(times) - len(reached)} scenes beyond its curve)") if times else "n/a"
            out.append(f"| {budget:g} | {cells[0]} | {cells[1]} | {cells[2]} | {cells[3]} | {mitsuba} |")
        out.append("")
    return "\n".join(out)


def _cell(value: Any) -> str:
    if value is None or value == "":
        return ""
    try:
        number = float(value)
    except (TypeError, ValueError):
        return str(value)
    if math.isnan(number):
        return ""
    return f"{number:.0f}" if number.is_integer() and abs(number) >= 1 else f"{number:.4g}"


def markdown_table(rows: list[dict[str, Any]], columns: Sequence[str]) -> str:
    """One line per row (scene, size, method, setting) with the given
    ``results.csv`` columns (numbers to 4 significant digits; a column a row
    lacks, such as a stat of another method, is left empty): a config's
    ``table`` key, the study's own table."""
    head = ["scene", "size", "method", "setting", *columns]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        lines.append("| " + " | ".join([str(r["scene"]), str(r["size"]), str(r["method"]), str(r["label"]), *(_cell(r.get(c)) for c in columns)]) + " |")
    return "\n".join(lines) + "\n"


def _curve(row: dict[str, Any], split: Sequence[str]) -> str:
    params = json.loads(row["params"]) if row.get("params") else {}
    return " ".join([str(row["method"]), *(f"{k}={params[k]}" for k in split if k in params)])


def _time_to(rows: list[dict[str, Any]], errors: Sequence[float], aggregate: str, split: Sequence[str], title: str) -> list[str]:
    reduce = np.mean if aggregate == "mean" else np.median
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault((_curve(r, split), str(r["label"])), []).append(r)
    curves: dict[str, list[tuple[float, float]]] = {}
    for (name, _), g in groups.items():
        err = [float(r[ERROR]) for r in g if math.isfinite(float(r[ERROR]))]
        if err:
            curves.setdefault(name, []).append((float(reduce([float(r["total_ms"]) for r in g])), float(reduce(err))))
    names = [n for n in curves if n != "mitsuba"] + (["mitsuba"] if "mitsuba" in curves else [])
    lines = [title, "", "| curve | " + " | ".join(f"time to penumbra RMSE {e:g} (ms) | time / Mitsuba's" for e in errors) + " |", "|---|" + "---|---|" * len(errors)]
    for name in names:
        cells = []
        for e in errors:
            t, bound = time_at_error(curves[name], e)
            peer = time_at_error(curves.get("mitsuba", []), e)
            ratio = t / peer[0] if math.isfinite(t) and math.isfinite(peer[0]) and peer[0] > 0 else math.nan
            # "~": a bound on either side makes the ratio approximate.
            cells += [f"{ {'=': '', '<=': '≤ ', '>=': '≥ '}[bound]}{t:.1f}", ("" if bound == "=" and peer[1] == "=" else "~ ") + f"{ratio:.2f}"]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return lines + [""]


def time_to_error_tables(rows: list[dict[str, Any]], errors: Sequence[float], aggregate: str = "median", split: Sequence[str] = ()) -> str:
    """Each curve's time to each penumbra RMSE in ``errors``, interpolated
    log-log along its Pareto front (:func:`time_at_error`; ≤ / ≥ mark the
    bounds), beside its time over Mitsuba's: first over the scenes (the
    ``aggregate``, ``mean`` or ``median``, of each setting's time and error),
    then per scene. A curve is a method, or a method at each value of the
    ``split`` parameters (``raytraced adaptive=True``)."""
    out = _time_to(rows, errors, aggregate, split, f"{aggregate.capitalize()}s over the scenes:")
    for scene in dict.fromkeys(r["scene"] for r in rows):
        out += _time_to([r for r in rows if r["scene"] == scene], errors, aggregate, split, f"{scene}:")
    return "\n".join(out)

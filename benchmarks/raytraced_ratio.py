"""Time to a penumbra visibility RMSE, from one `penumbra bench` run: method
`raytraced` in plain and in adaptive mode (separate curves) against
Mitsuba's estimator and `reference`, each interpolated log-log along its
Pareto front of (mean time, mean error) over the run's scenes
(`penumbra.bench.time_at_error`), and per scene.

    python benchmarks/raytraced_ratio.py benchmarks/results/raytraced/results.csv [--error 0.02]
"""

from __future__ import annotations

import argparse
import csv
import json
import math
from collections import defaultdict

import numpy as np

from penumbra.bench import ERROR, time_at_error


def curve_name(row: dict[str, str]) -> str:
    if row["method"] != "raytraced":
        return row["method"]
    return "raytraced adaptive" if json.loads(row["params"]).get("adaptive") else "raytraced plain"


def curves(rows: list[dict[str, str]]) -> dict[str, list[tuple[float, float]]]:
    groups: dict[tuple[str, str], list[dict[str, str]]] = defaultdict(list)
    for row in rows:
        groups[(curve_name(row), row["label"])].append(row)
    out: dict[str, list[tuple[float, float]]] = defaultdict(list)
    for (name, _), group in groups.items():
        out[name].append((float(np.mean([float(r["total_ms"]) for r in group])), float(np.mean([float(r[ERROR]) for r in group]))))
    return out


def table(rows: list[dict[str, str]], error: float, title: str) -> str:
    found = curves(rows)
    lines = [f"{title}", "", "| curve | time to penumbra RMSE {:g} (ms) | time / Mitsuba's |".format(error), "|---|---|---|"]
    mitsuba = time_at_error(found.get("mitsuba", []), error)
    for name in ("raytraced plain", "raytraced adaptive", "reference", "mitsuba"):
        if name not in found:
            continue
        t, bound = time_at_error(found[name], error)
        mark = {"=": "", "<=": "≤ ", ">=": "≥ "}[bound]
        ratio = t / mitsuba[0] if math.isfinite(t) and math.isfinite(mitsuba[0]) and mitsuba[0] > 0 else math.nan
        rmark = "" if bound == "=" and mitsuba[1] == "=" else "~ "
        lines.append(f"| {name} | {mark}{t:.1f} | {rmark}{ratio:.2f} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("results")
    parser.add_argument("--error", type=float, default=0.02)
    args = parser.parse_args()
    with open(args.results, newline="") as f:
        rows = list(csv.DictReader(f))
    print(table(rows, args.error, "Means over the scenes:"))
    for scene in dict.fromkeys(r["scene"] for r in rows):
        print(table([r for r in rows if r["scene"] == scene], args.error, f"{scene}:"))


if __name__ == "__main__":
    main()

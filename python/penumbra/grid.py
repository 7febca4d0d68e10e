"""Parameter grids and result rows: the one expander and the one row schema
that :func:`penumbra.sweep` and ``penumbra bench`` share.

A grid is a dict mapping each parameter to a list of values (their
Cartesian product, the last key varying fastest) or to one value; a list of
grids is each expanded in turn; ``None`` is one set of defaults.

Every row that records a render has the columns of :func:`result_columns`:
``total_ms``, ``timing_source``, ``ms_<pass>`` (milliseconds of each pass
that ran), ``stat_<name>`` (each stat) and ``reused`` (the passes whose
cached outputs the render reused, comma-separated).
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, Union

import numpy as np

from penumbra.errors import ParameterError

if TYPE_CHECKING:
    from penumbra.render import RenderResult

__all__ = ["ParamGrid", "expand", "label", "result_columns", "TIMING_PREFIX", "STAT_PREFIX"]

ParamGrid = Union[Mapping[str, Any], Sequence[Mapping[str, Any]], None]

#: Column prefix of a pass's time in milliseconds.
TIMING_PREFIX = "ms_"
#: Column prefix of a stat.
STAT_PREFIX = "stat_"

# Values that list a parameter's values; anything else (a string included) is one value.
_LISTS = (list, tuple, range, np.ndarray)


def _one_grid(grid: Mapping[str, Any]) -> list[dict[str, Any]]:
    keys = list(grid)
    if not all(isinstance(k, str) for k in keys):
        raise ParameterError(f"parameter names must be strings, got {keys}")
    values = [list(v) if isinstance(v, _LISTS) else [v] for v in grid.values()]
    return [dict(zip(keys, combo)) for combo in itertools.product(*values)]


def expand(params: ParamGrid, *, unique: bool = False) -> list[dict[str, Any]]:
    """The parameter sets of ``params``, in order: a dict's product (a list,
    tuple, range or array value varies, any other value is fixed), a list of
    dicts each expanded in turn, or ``[{}]`` for ``None``. ``unique`` drops
    repeated sets (the first is kept)."""
    if params is None:
        return [{}]
    if isinstance(params, Mapping):
        sets = _one_grid(params)
    elif isinstance(params, Sequence) and not isinstance(params, (str, bytes)):
        sets = []
        for i, grid in enumerate(params):
            if not isinstance(grid, Mapping):
                raise ParameterError(f"params[{i}] must be a dict of parameter values, got {type(grid).__name__}")
            sets += _one_grid(grid)
    else:
        raise ParameterError(f"params must be a dict of lists, a list of dicts or None, got {type(params).__name__}")
    if unique:
        distinct: list[dict[str, Any]] = []
        for p in sets:
            if p not in distinct:
                distinct.append(p)
        return distinct
    return sets


def label(params: Mapping[str, Any]) -> str:
    """A short, stable name of a parameter set ("default" when empty)."""
    return " ".join(f"{k}={v}" for k, v in sorted(params.items())) or "default"


def result_columns(result: RenderResult, *, timings: Mapping[str, float] | None = None, total_ms: float | None = None) -> dict[str, Any]:
    """The row columns of one render: ``total_ms``, ``timing_source``,
    ``ms_<pass>``, ``stat_<name>`` and ``reused``. ``timings`` and
    ``total_ms`` replace the result's own (a benchmark's medians over repeats)."""
    row: dict[str, Any] = {
        "total_ms": result.total_ms if total_ms is None else total_ms,
        "timing_source": result.timing_source,
    }
    row.update({f"{TIMING_PREFIX}{name}": ms for name, ms in (result.timings if timings is None else timings).items()})
    row.update({f"{STAT_PREFIX}{name}": value for name, value in result.stats.items()})
    row["reused"] = ",".join(result.reused_passes)
    return row

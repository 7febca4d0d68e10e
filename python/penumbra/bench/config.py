"""``penumbra bench`` configuration: the TOML file's keys, their checks and
the parameter sets of each method's grids."""

from __future__ import annotations

import os
import tomllib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from penumbra import scenes
from penumbra.errors import ParameterError
from penumbra.grid import expand as expand_grids
from penumbra.grid import label

__all__ = ["BenchConfig", "load_config", "expand", "label"]

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


def expand(grids: Iterable[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """Every parameter set of a method's grids, in order, without repeats
    (:func:`penumbra.grid.expand`, the expander sweeps use too)."""
    return expand_grids(list(grids), unique=True)

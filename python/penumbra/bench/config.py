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
    "large": dict,
    "radiance": bool,
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
    #: Radiance too (ground truth, metrics, Mitsuba's radiance timing); false:
    #: visibility only, the benchmark's question, at a fraction of Mitsuba's time.
    radiance: bool = True
    #: method -> list of grids; a grid maps each parameter to a list of values
    #: (their product) or to one value.
    methods: dict[str, list[dict[str, Any]]] = field(default_factory=dict)
    #: ``mitsuba_spp`` (list) and ``reference_samples`` (list).
    peers: dict[str, Any] = field(default_factory=dict)
    #: ``scene``, ``methods`` (list), ``sizes`` (list), ``radii`` (list), ``ground_truth_spp``.
    scaling: dict[str, Any] = field(default_factory=dict)
    #: A second part at another size: ``scenes``, ``width``, ``height`` and
    #: optionally ``ground_truth_spp``, ``methods``, ``peers`` (else the main ones).
    large: dict[str, Any] = field(default_factory=dict)


def _checked(values: dict[str, Any], where: str) -> dict[str, Any]:
    for key, value in values.items():
        if key == "quick":
            continue
        if key not in _KEYS:
            raise ParameterError(f"{where}: unknown key {key!r} (known: {sorted(_KEYS)})")
        want = _KEYS[key]
        if want is float and isinstance(value, int) and not isinstance(value, bool):
            continue
        if want is bool:
            if not isinstance(value, bool):
                raise ParameterError(f"{where}: {key!r} must be true or false, got {value!r}")
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
    values["methods"] = _grids(values.get("methods", {}), f"{path}")
    values["scenes"] = _scene_names(values.get("scenes", []), f"{path}")
    if values.get("large"):
        big = dict(values["large"])
        for key in ("scenes", "width", "height"):
            if key not in big:
                raise ParameterError(f"{path}: [large] needs {key!r} (scenes, width, height; optionally ground_truth_spp, methods, peers)")
        extra = set(big) - {"scenes", "width", "height", "ground_truth_spp", "methods", "peers"}
        if extra:
            raise ParameterError(f"{path}: [large]: unknown keys {sorted(extra)}")
        for key in ("width", "height", "ground_truth_spp"):
            if key in big and (not isinstance(big[key], int) or isinstance(big[key], bool) or big[key] < 1):
                raise ParameterError(f"{path}: [large] {key!r} must be an integer of at least 1, got {big[key]!r}")
        big["scenes"] = _scene_names(big["scenes"], f"{path} [large]")
        if "methods" in big:
            big["methods"] = _grids(big["methods"], f"{path} [large]")
        values["large"] = big
    name = path.stem + ("_quick" if quick else "")
    return BenchConfig(name=name, **values)


def _grids(methods_: Any, where: str) -> dict[str, list[dict[str, Any]]]:
    if not isinstance(methods_, dict):
        raise ParameterError(f"{where}: methods must be a table")
    out = {}
    for method, grids in methods_.items():
        grids = [grids] if isinstance(grids, dict) else grids
        if not isinstance(grids, list) or not all(isinstance(g, dict) for g in grids):
            raise ParameterError(f"{where}: methods.{method} must be a table or a list of tables of parameters")
        out[method] = grids
    return out


def _scene_names(entries: Any, where: str) -> list[str]:
    """The scene names with ``generated:<first>..<last>`` written out, each
    one known (:func:`penumbra.scenes.get`'s names)."""
    if not isinstance(entries, list):
        raise ParameterError(f"{where}: 'scenes' must be a list")
    unknown = []
    for entry in entries:
        try:
            scenes.expand_names([entry])
        except ParameterError:
            unknown.append(entry)
    if unknown:
        raise ParameterError(f"{where}: unknown scenes {unknown} (built-in: {scenes.names()}; from the shared meshes: {scenes.real_names()})")
    return scenes.expand_names(entries)


def expand(grids: Iterable[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """Every parameter set of a method's grids, in order, without repeats
    (:func:`penumbra.grid.expand`, the expander sweeps use too)."""
    return expand_grids(list(grids), unique=True)

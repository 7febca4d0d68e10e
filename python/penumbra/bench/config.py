"""``penumbra bench`` configuration: the TOML file's keys, their checks and
the parameter sets of each method's grids."""

from __future__ import annotations

import os
import tomllib
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from penumbra import forms, scenes
from penumbra.errors import ParameterError
from penumbra.grid import expand as expand_grids
from penumbra.grid import label
from penumbra.scene import Camera, Mesh, Scene

__all__ = ["BenchConfig", "SceneVariant", "load_config", "expand", "label"]

#: A scene table's ``form``: the mesh as :mod:`penumbra.forms` hands it over (issue 27).
MESH_FORMS: dict[str, Callable[[Mesh], Mesh | list[Mesh]]] = {"soup": forms.soup, "split": forms.split, "doubled": forms.doubled, "reversed": forms.reversed_windings, "slivers": forms.with_slivers}

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
    "table": list,
    "sampling_noise": bool,
    "resolution_error": int,
    "time_to_error": dict,
    "against": dict,
    "columns": list,
}


@dataclass(frozen=True)
class SceneVariant:
    """One scene of a run: a scene name (:func:`penumbra.scenes.get`) and,
    from a table entry of ``scenes``, another light radius or, for a
    ``mesh:<file>`` name, another placement (:func:`penumbra.scenes.from_mesh`'s
    ``setup``: ``close``, the name's own, ``default`` or ``wide_floor``).
    ``label`` names it in the results."""

    scene: str
    light_radius: float | None = None
    setup: str | None = None
    label: str = ""
    #: The mesh file's mesh in another form (:data:`MESH_FORMS`: a triangle soup, split, ...).
    form: str | None = None
    #: Another camera: ``eye``, ``target`` and optionally ``up``, ``fov_y`` (:class:`penumbra.Camera`).
    camera: tuple[tuple[str, Any], ...] = ()

    def build(self, width: int, height: int) -> Scene:
        """The scene at ``width`` x ``height``, named by its label."""
        if self.setup is None:
            scene = scenes.get(self.scene, width=width, height=height, light_radius=self.light_radius)
        else:
            # Built as from_mesh builds it (the light's own intensity at this radius), as real_mesh_suite does.
            root = scenes.meshes_folder()
            if root is None:
                raise ParameterError(f"scene {self.label!r} needs the shared meshes: set PENUMBRA_MESHES")
            radius = 0.5 if self.light_radius is None else self.light_radius
            scene = scenes.from_mesh(str(root / self.scene.partition(":")[2]), width=width, height=height, light_radius=radius, setup=self.setup)
            if self.form is not None:  # from_mesh's scene: the ground slab, then the mesh
                scene = forms.replace_mesh(scene, 1, MESH_FORMS[self.form](scene.meshes[1]))
        if self.camera:
            scene = scene.with_camera(Camera(**dict(self.camera), width=width, height=height))
        return replace(scene, name=self.label or self.scene)


@dataclass
class BenchConfig:
    """What to run (see ``benchmarks/bench.toml`` for every key)."""

    name: str
    #: The scenes' labels, in order: a scene name, or a variant's label (``variants``).
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
    #: Columns of ``results.csv`` written as ``table.md``: one line per scene
    #: and configuration (empty: no table).
    table: list[str] = field(default_factory=list)
    #: Each row's own noise too (``sampling_noise_<metric>``, :func:`penumbra.metrics.own_noise`):
    #: the configuration again with its ``seed`` + 1 (methods that take one; Mitsuba's peer rows at seed 3).
    sampling_noise: bool = False
    #: A factor k > 1: each row's resolution error too (``resolution_error_visibility_rmse`` and
    #: ``_penumbra``): the RMSE against the same configuration at k times its ``map_size``.
    resolution_error: int = 0
    #: ``errors`` (list), optional ``aggregate`` (``mean`` or ``median``, the default) and ``split``
    #: (parameters whose values are curves of their own): ``time_to_error.md``, each curve's time to
    #: each error over the scenes and per scene, beside Mitsuba's (:func:`penumbra.bench.report.time_to_error_tables`).
    time_to_error: dict[str, Any] = field(default_factory=dict)
    #: method (or ``"*"``, every method) -> name -> ``{ method, keep, set, when, threshold }``: each row of
    #: the method whose parameters include ``when``'s set against another configuration of the same scene,
    #: ``method`` (default: the row's) with the row's parameters named in ``keep`` (default: all) and those
    #: of ``set`` (rows of a method that does not take them are left alone): ``vs_<name>_max``, ``_mean``, ``_rmse`` (over geometry
    #: pixels), ``_rmse_penumbra`` (the truth's), ``_over`` (geometry pixels off by more than ``threshold``,
    #: a number or ``"one_sample"``: 1 / the row's ``n_samples``) and, where that configuration is a row of
    #: the run, ``_time`` (the row's time over its).
    against: dict[str, dict[str, dict[str, Any]]] = field(default_factory=dict)
    #: ``"module:function"`` names: each called with a row's render result and scene, its dict of numbers
    #: added to the row (the renders then read back every image: ``position``, ``normal``); a study's
    #: own measure, such as :func:`penumbra.transition.contact_widths`.
    columns: list[str] = field(default_factory=list)
    #: Every scene label of the run (both parts) -> what to build.
    variants: dict[str, SceneVariant] = field(default_factory=dict)

    def scene(self, label: str, width: int, height: int) -> Scene:
        """The run's scene ``label`` at ``width`` x ``height``."""
        return self.variants.get(label, SceneVariant(label, label=label)).build(width, height)


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
    if values.get("resolution_error", 0) not in range(2, 65) and values.get("resolution_error", 0) != 0:
        raise ParameterError(f"{where}: 'resolution_error' is a factor of the map size of at least 2 (or 0: none), got {values['resolution_error']}")
    if "warmup" in values and values["warmup"] < 0:
        raise ParameterError(f"{where}: 'warmup' must be at least 0, got {values['warmup']}")
    return values


def load_config(path: str | os.PathLike[str], quick: bool = False, overrides: Iterable[str] = ()) -> BenchConfig:
    """Reads a benchmark config; ``quick`` applies its ``[quick]`` table, then
    each of ``overrides`` (``key=<TOML value>``: ``scenes=["cornell_box"]``,
    ``large={}``) replaces a top-level key."""
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
    for text in overrides:
        key, _, value = text.partition("=")
        try:
            values.update(_checked(tomllib.loads(f"{key.strip()} = {value}"), f"{path} --set"))
        except tomllib.TOMLDecodeError as e:
            raise ParameterError(f"--set takes key=<TOML value> (scenes=[\"cornell_box\"], size=64), got {text!r}: {e}") from e
    values["methods"] = _grids(values.get("methods", {}), f"{path}")
    variants: dict[str, SceneVariant] = {}
    values["scenes"] = _scene_names(values.get("scenes", []), f"{path}", variants)
    if not all(isinstance(c, str) and ":" in c for c in values.get("columns", [])):
        raise ParameterError(f"{path}: 'columns' must be a list of \"module:function\" names")
    if not all(isinstance(c, str) for c in values.get("table", [])):
        raise ParameterError(f"{path}: 'table' must be a list of results.csv column names")
    tte = values.get("time_to_error")
    if tte and (not isinstance(tte.get("errors"), list) or not tte["errors"] or set(tte) - {"errors", "aggregate", "split"}
                or tte.get("aggregate", "median") not in ("mean", "median") or not isinstance(tte.get("split", []), list)):
        raise ParameterError(f"{path}: [time_to_error] takes 'errors' (a list of penumbra RMSEs), optionally 'aggregate' (mean or median) and 'split' (parameter names); got {tte!r}")
    for method, entries in values.get("against", {}).items():
        for name, entry in (entries.items() if isinstance(entries, dict) else [("", None)]):
            if (not isinstance(entry, dict) or set(entry) - {"method", "keep", "set", "when", "threshold"} or not isinstance(entry.get("keep", []), list)
                    or not isinstance(entry.get("set", {}), dict) or not isinstance(entry.get("when", {}), dict) or not (entry.get("threshold", 0.01) == "one_sample" or isinstance(entry.get("threshold", 0.01), (int, float)))):
                raise ParameterError(f"{path}: [against.{method}] maps names to tables of 'method', 'keep' (a list), 'set' (a table), 'when' (a table), 'threshold' (a number or \"one_sample\"); got {name!r} = {entry!r}")
    if values.get("large"):
        big = dict(values["large"])
        for key in ("scenes", "width", "height"):
            if key not in big:
                raise ParameterError(f"{path}: [large] needs {key!r} (scenes, width, height; optionally ground_truth_spp, methods, peers, sampling_noise, resolution_error)")
        extra = set(big) - {"scenes", "width", "height", "ground_truth_spp", "methods", "peers", "sampling_noise", "resolution_error"}
        _checked({k: v for k, v in big.items() if k in ("sampling_noise", "resolution_error")}, f"{path} [large]")
        if extra:
            raise ParameterError(f"{path}: [large]: unknown keys {sorted(extra)}")
        for key in ("width", "height", "ground_truth_spp"):
            if key in big and (not isinstance(big[key], int) or isinstance(big[key], bool) or big[key] < 1):
                raise ParameterError(f"{path}: [large] {key!r} must be an integer of at least 1, got {big[key]!r}")
        big["scenes"] = _scene_names(big["scenes"], f"{path} [large]", variants)
        if "methods" in big:
            big["methods"] = _grids(big["methods"], f"{path} [large]")
        values["large"] = big
    name = path.stem + ("_quick" if quick else "")
    return BenchConfig(name=name, variants=variants, **values)


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


_VARIANT_KEYS = {"scene", "light_radius", "setup", "label", "form", "camera"}


def _variants(entry: dict[str, Any], where: str) -> list[SceneVariant]:
    """A ``scenes`` table entry written out: every scene of ``scene`` (a name
    or a list) at every radius of ``light_radius`` (a number or a list)."""
    extra = set(entry) - _VARIANT_KEYS
    if extra or "scene" not in entry:
        raise ParameterError(f"{where}: a scene table takes 'scene' and optionally 'light_radius', 'setup', 'label', 'form', 'camera'; got {sorted(entry)}")
    names_ = entry["scene"] if isinstance(entry["scene"], list) else [entry["scene"]]
    radii = entry.get("light_radius")
    radii = radii if isinstance(radii, list) else [radii]
    if not all(r is None or (isinstance(r, (int, float)) and not isinstance(r, bool) and r >= 0) for r in radii):
        raise ParameterError(f"{where}: 'light_radius' must be a number of at least 0 or a list of them, got {entry['light_radius']!r}")
    setup = entry.get("setup")
    if setup is not None and (setup not in scenes.SETUPS or not all(isinstance(n, str) and n.startswith("mesh:") for n in names_)):
        raise ParameterError(f"{where}: 'setup' (one of {list(scenes.SETUPS)}) places 'mesh:<file>' scenes only, got {entry!r}")
    form = entry.get("form")
    if form is not None and (form not in MESH_FORMS or setup is None):
        raise ParameterError(f"{where}: 'form' (one of {list(MESH_FORMS)}) reshapes the mesh of a scene with a 'setup', got {entry!r}")
    camera = entry.get("camera", {})
    if camera and (not isinstance(camera, dict) or not {"eye", "target"} <= set(camera) or set(camera) - {"eye", "target", "up", "fov_y"}):
        raise ParameterError(f"{where}: a scene's 'camera' takes 'eye', 'target' and optionally 'up', 'fov_y'; got {camera!r}")
    if "label" in entry and len(names_) * len(radii) != 1:
        raise ParameterError(f"{where}: 'label' names one scene, not the {len(names_) * len(radii)} of {entry!r}")
    out = []
    for name in scenes.expand_names(names_):
        for r in radii:
            default = name + (f" {setup}" if setup else "") + (f" {form}" if form else "") + ("" if r is None else f" r={r:g}")
            out.append(SceneVariant(name, None if r is None else float(r), setup, entry.get("label", default), form, tuple((k, tuple(v) if isinstance(v, list) else v) for k, v in sorted(camera.items()))))
    return out


def _scene_names(entries: Any, where: str, variants: dict[str, SceneVariant]) -> list[str]:
    """The scene labels of ``entries`` with ``generated:<first>..<last>``
    written out and table entries expanded (each recorded in ``variants``),
    each scene name known (:func:`penumbra.scenes.get`'s names)."""
    if not isinstance(entries, list):
        raise ParameterError(f"{where}: 'scenes' must be a list")
    unknown = []
    out: list[str] = []
    for entry in entries:
        try:
            if isinstance(entry, dict):
                found = _variants(entry, where)
                variants.update((v.label, v) for v in found)
                out += [v.label for v in found]
            elif entry in variants:  # a [large] part naming a variant of the main part's
                out.append(entry)
            else:
                out += scenes.expand_names([entry])
        except ParameterError as e:
            if isinstance(entry, dict) and "unknown scene" not in str(e) and "generated" not in str(e):
                raise
            unknown.append(entry)
    if unknown:
        raise ParameterError(f"{where}: unknown scenes {unknown} (built-in: {scenes.names()}; from the shared meshes: {scenes.real_names()})")
    return out


def expand(grids: Iterable[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """Every parameter set of a method's grids, in order, without repeats
    (:func:`penumbra.grid.expand`, the expander sweeps use too)."""
    return expand_grids(list(grids), unique=True)

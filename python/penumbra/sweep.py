"""Parameter sweeps: many renders of one or several scenes with one or several
methods, measured against ground truth, as one pandas DataFrame.

A sweep renders its configurations in order on one renderer, whose pass
cache (see :class:`penumbra.Renderer`) reuses every pass a parameter change
does not affect: order the grid so that late-stage parameters (PVMF's
``n_blur``, PVM's ``falloff``) vary fastest, which a dict grid does when they
are its last keys.

Configurations can be spread over processes with any
``concurrent.futures.Executor``; each worker process builds its own renderer
once (a module-level one, with its own pass cache) and renders contiguous
chunks of the grid, so late-stage sweeps keep their reuse within a chunk.
The same call runs on a Dask cluster (``pip install penumbra[cluster]``):
``executor=`` takes a ``distributed.Client`` or its ``get_executor()``; the
scenes and ground truth then travel to the workers once, through the
scheduler, instead of with every chunk (docs/sweeps.md).
"""

from __future__ import annotations

import concurrent.futures
import itertools
import math
import os
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Union

import numpy as np

from penumbra.errors import ParameterError, SceneError
from penumbra.grid import ParamGrid, expand, result_columns
from penumbra.render import IMAGES, Renderer, RenderResult
from penumbra.scene import Camera, Scene

if TYPE_CHECKING:
    import pandas as pd

    from penumbra.mitsuba import GroundTruth

__all__ = ["sweep", "grid"]

#: Images kept per configuration with ``keep_images=True``.
DEFAULT_IMAGES = ("radiance", "visibility")

Scenes = Union[Scene, Mapping[str, Scene], Sequence[Scene]]


def grid(params: ParamGrid) -> list[dict[str, Any]]:
    """The parameter sets of ``params`` (:func:`penumbra.grid.expand`, the
    expander ``penumbra bench`` uses too): a dict's Cartesian product, the
    last key varying fastest (a list value varies, any other value is
    fixed); a list of dicts, each expanded in turn; ``None``, one set of
    defaults. Repeated sets are kept: one row each."""
    return expand(params)


def _kept_images(keep_images: Any) -> tuple[str, ...]:
    if keep_images is True:
        return DEFAULT_IMAGES
    if keep_images is False or keep_images is None:
        return ()
    names = [keep_images] if isinstance(keep_images, str) else keep_images
    if not isinstance(names, (list, tuple)) or not all(isinstance(n, str) for n in names):
        raise ParameterError(f"keep_images must be True, False or a list of image names, got {keep_images!r}")
    unknown = [n for n in names if n not in IMAGES]
    if unknown:
        raise ParameterError(f"keep_images: no image named {unknown}; a sweep's renders have {list(IMAGES)}")
    return tuple(names)


def _scenes(scenes: Scenes) -> dict[str, Scene]:
    if isinstance(scenes, Scene):
        return {"scene": scenes}
    if isinstance(scenes, Mapping):
        named = {str(k): v for k, v in scenes.items()}
    elif isinstance(scenes, Sequence) and not isinstance(scenes, (str, bytes)):
        named = {f"scene{i}": s for i, s in enumerate(scenes)}
    else:
        raise SceneError(f"scenes must be a penumbra.Scene, a dict or a list of them, got {type(scenes).__name__}")
    if not named:
        raise SceneError("a sweep needs at least one scene")
    for name, s in named.items():
        if not isinstance(s, Scene):
            raise SceneError(f"scene {name!r} is a {type(s).__name__}, not a penumbra.Scene")
    return named


@dataclass
class _Task:
    """One configuration, as it travels to a worker."""

    index: int
    scene_name: str
    method: str
    params: dict[str, Any]


@dataclass
class _Chunk:
    """Contiguous configurations, rendered in order on one renderer."""

    scenes: dict[str, Scene]
    camera: Camera | None
    tasks: list[_Task]
    ground_truth: dict[str, GroundTruth]
    keep_images: tuple[str, ...]
    #: Every parameter named in the grid: a column each, with the value in effect.
    columns: tuple[str, ...] = ()


@dataclass
class _Shared:
    """What every chunk of a sweep reads: sent to a Dask cluster once
    (``Client.scatter``), not with each chunk."""

    scenes: dict[str, Scene]
    ground_truth: dict[str, GroundTruth]


_PROCESS_RENDERER: Renderer | None = None


def process_renderer() -> Renderer:
    """This process's sweep renderer, built on first use (pass cache on):
    the one in-process sweeps use by default, and each executor worker's own."""
    global _PROCESS_RENDERER
    if _PROCESS_RENDERER is None:
        _PROCESS_RENDERER = Renderer()
    return _PROCESS_RENDERER


def _row(task: _Task, result: RenderResult, chunk: _Chunk) -> tuple[dict[str, Any], dict[str, np.ndarray] | None]:
    from penumbra import metrics

    row: dict[str, Any] = {"config": task.index, "scene": task.scene_name, "method": task.method}
    row.update({k: result.params.get(k, task.params.get(k)) for k in chunk.columns})
    row.update(result_columns(result))
    row["worker_pid"] = os.getpid()
    gt = chunk.ground_truth.get(task.scene_name)
    if gt is not None:
        row.update(metrics.compare(result, gt))
    images = {k: result.images[k] for k in chunk.keep_images if k in result.images} if chunk.keep_images else None
    return row, images


def _describe(task: _Task) -> str:
    params = ", ".join(f"{k}={v!r}" for k, v in task.params.items()) or "defaults"
    return f"sweep configuration {task.index} (scene {task.scene_name!r}, method {task.method!r}, {params}) on {_host()} pid {os.getpid()}"


def _host() -> str:
    import socket

    return socket.gethostname()


def _with_configuration(error: Exception, task: _Task) -> Exception:
    """``error`` naming the configuration that raised it: the same class with
    the configuration after the message where the class takes a message
    (every Penumbra error does), else the original with a note. Either way
    ``sweep_config`` holds the configuration as a dict."""
    where = _describe(task)
    try:
        named = type(error)(f"{error}; in {where}")
    except Exception:
        named = error
        named.add_note(f"in {where}")
    named.sweep_config = {"config": task.index, "scene": task.scene_name, "method": task.method, "params": dict(task.params)}  # type: ignore[attr-defined]
    return named


def _run_chunk(chunk: _Chunk, renderer: Renderer | None = None) -> list[tuple[dict[str, Any], dict[str, np.ndarray] | None]]:
    """Renders a chunk in order (a worker's entry point; importable, so that
    process pools and Dask can ship it). A configuration that raises stops
    the chunk with its error, naming the configuration."""
    renderer = renderer or process_renderer()
    out = []
    for task in chunk.tasks:
        try:
            result = renderer.render(
                chunk.scenes[task.scene_name], task.method, camera=chunk.camera, outputs=_outputs_needed(chunk, task), **task.params
            )
            out.append(_row(task, result, chunk))
        except Exception as e:
            named = _with_configuration(e, task)
            if named is e:
                raise
            raise named from e
    return out


def _run_shared_chunk(chunk: _Chunk, shared: _Shared) -> list[tuple[dict[str, Any], dict[str, np.ndarray] | None]]:
    """A Dask worker's entry point: the chunk with the scenes and ground
    truth scattered once for the whole sweep."""
    chunk.scenes, chunk.ground_truth = shared.scenes, shared.ground_truth
    return _run_chunk(chunk)


def _outputs_needed(chunk: _Chunk, task: _Task) -> list[str]:
    """The images a configuration's row needs: those kept, and what the
    metrics read (visibility, object ids, and radiance where the ground
    truth has it). Nothing else is read back, and shading runs only for
    radiance."""
    needed = set(chunk.keep_images)
    gt = chunk.ground_truth.get(task.scene_name)
    if gt is not None:
        needed |= {"visibility", "object_id"} | ({"radiance"} if "radiance" in gt.images else set())
    return [name for name in IMAGES if name in needed]


def _ground_truths(
    ground_truth: Any, scenes: dict[str, Scene], camera: Camera | None, spp: int, renderer: Renderer | None
) -> dict[str, GroundTruth]:
    from penumbra.mitsuba import GroundTruth, ground_truth as render_ground_truth
    from penumbra.truth import raytraced_truth

    if ground_truth is None or ground_truth is False:
        return {}
    if ground_truth == "raytraced":
        # The engine's own truth, with a second seed for its noise floor.
        target = renderer or process_renderer()
        return {name: raytraced_truth(s, camera, n_samples=spp, noise_seed=1, renderer=target) for name, s in scenes.items()}
    if ground_truth is True or ground_truth == "mitsuba":
        # With a second seed, as penumbra.compare: every metric gets its noise floor.
        return {name: render_ground_truth(s, camera, spp=spp, noise_seed=1) for name, s in scenes.items()}
    if isinstance(ground_truth, GroundTruth):
        if len(scenes) != 1:
            raise ParameterError("one GroundTruth given for several scenes; pass a dict of scene name to GroundTruth")
        return {next(iter(scenes)): ground_truth}
    if isinstance(ground_truth, Mapping):
        missing = [n for n in scenes if n not in ground_truth]
        if missing:
            raise ParameterError(f"no ground truth for scene(s) {missing}")
        return {n: ground_truth[n] for n in scenes}
    raise ParameterError(
        f"ground_truth must be None, True ('mitsuba'), 'raytraced', a GroundTruth or a dict of them, got {ground_truth!r}"
    )


def _dask_client(executor: Any) -> tuple[Any, dict[str, Any]] | None:
    """The ``distributed.Client`` behind ``executor`` (the client itself or
    its ``get_executor()``) and the submit options the executor was made
    with; None for any other executor. Recognised by its module, so that
    distributed is imported only when given one of its objects."""
    module = type(executor).__module__ or ""
    if not (module == "distributed" or module.startswith("distributed.")):
        return None
    if type(executor).__name__ == "ClientExecutor":
        return executor._client, dict(getattr(executor, "_kwargs", {}))
    if hasattr(executor, "scatter") and hasattr(executor, "submit") and hasattr(executor, "nthreads"):
        return executor, {}
    raise ParameterError(f"executor: a {module}.{type(executor).__name__} is neither a distributed.Client nor its get_executor()")


def _worker_count(executor: Any, client: Any) -> int:
    """Workers that render at once: a Dask cluster's worker threads (each
    worker process's threads, summed), a pool's ``_max_workers``."""
    if client is not None:
        threads = sum(int(n) for n in client.nthreads().values())
        return max(threads, 1)
    workers = getattr(executor, "_max_workers", None)
    return int(workers) if isinstance(workers, int) and workers > 0 else os.cpu_count() or 1


def _progress_bar(total: int, progress: bool | None) -> Any:
    show = progress if progress is not None else sys.stderr.isatty()
    if not show:
        return None
    from tqdm import tqdm

    return tqdm(total=total, unit="render", desc="sweep")


def sweep(
    scenes: Scenes,
    method: str | Sequence[str],
    params: ParamGrid = None,
    *,
    ground_truth: bool | str | GroundTruth | Mapping[str, GroundTruth] | None = None,
    ground_truth_spp: int = 256,
    camera: Camera | None = None,
    renderer: Renderer | None = None,
    executor: concurrent.futures.Executor | Any | None = None,
    chunksize: int | None = None,
    keep_images: bool | Sequence[str] = False,
    progress: bool | None = None,
) -> pd.DataFrame:
    """Renders every (scene, method, parameter set) and returns one row each.

    ``scenes``: a :class:`~penumbra.Scene`, a dict of name to scene, or a
    list (named ``scene0``, ``scene1``, ...). ``method``: a method name or a
    list of them. ``params``: a dict of lists (their product, the last key
    varying fastest), a list of dicts, or None (defaults). Configurations run
    scene by scene, then method by method, then through the grid in order.

    ``ground_truth``: None; True (or ``"mitsuba"``) to render Mitsuba ground
    truth of each scene at ``ground_truth_spp``, with a second seed for the
    noise floor as :func:`penumbra.compare` does (both cached under
    ``$PENUMBRA_CACHE_DIR``); ``"raytraced"`` for the engine's own truth, method
    ``raytraced`` at ``ground_truth_spp`` light samples with a second seed
    (:func:`penumbra.truth.raytraced_truth`, not cached; give it thousands); a
    :class:`~penumbra.mitsuba.GroundTruth` for a single scene; or a dict of
    scene name to one. With it, every row has every metric of
    :func:`penumbra.metrics.compare`.

    Columns: ``config`` (the index in run order), ``scene``, ``method``, each
    parameter the grid names (the value in effect: a method's default where a
    set leaves it out), then the row schema ``penumbra bench`` shares
    (:func:`penumbra.grid.result_columns`): ``total_ms``, ``timing_source``,
    ``ms_<pass>`` (ms, only for passes that ran: a pass the renderer's cache
    reused has none, NaN in its column), ``stat_<name>`` for each stat
    (``stat_reused_passes`` and ``stat_reused_<pass>`` say what was reused),
    ``reused`` (the reused passes' names, comma-separated); then
    ``worker_pid`` and the metrics. ``keep_images=True`` adds an ``images``
    column of dicts holding radiance and visibility; a list of image names
    (of ``radiance``, ``visibility``, ``depth``, ``normal``, ``position``,
    ``object_id``) keeps those instead.

    ``renderer``: the renderer for in-process sweeps (default: one per
    process, kept between sweeps, so repeated sweeps reuse its cache).
    ``executor``: any ``concurrent.futures.Executor``, or a Dask
    ``distributed.Client`` (or its ``get_executor()``); configurations go to
    it in contiguous chunks of ``chunksize`` (default: about two chunks per
    worker: a pool's ``max_workers``, a Dask cluster's worker threads), each
    worker rendering with its own process-wide renderer, so a chunk's
    configurations reuse each other's passes. The ground truth is rendered
    once per scene, in this process, before any chunk is sent; on Dask the
    scenes and ground truth are scattered to the cluster once and every
    chunk reads them from there. A configuration that raises stops the
    sweep with its error, of the same class, naming the configuration (its
    index, scene, method and parameters, and the worker's host and pid;
    ``error.sweep_config`` holds them as a dict). Timings from concurrent
    workers share the machine's cores: time with ``executor=None``.

    ``progress``: a tqdm bar, advanced as each chunk comes back (default:
    only when stderr is a terminal).
    """
    import pandas as pd

    named = _scenes(scenes)
    methods = [method] if isinstance(method, str) else list(method)
    if not methods or not all(isinstance(m, str) for m in methods):
        raise ParameterError(f"method must be a name or a list of names, got {method!r}")
    sets = grid(params)
    kept = _kept_images(keep_images)
    columns = tuple(dict.fromkeys(k for p in sets for k in p))
    truths = _ground_truths(ground_truth, named, camera, ground_truth_spp, renderer)
    tasks = [
        _Task(i, scene_name, m, p)
        for i, (scene_name, m, p) in enumerate(itertools.product(named, methods, sets))
    ]
    rows: list[tuple[dict[str, Any], dict[str, np.ndarray] | None]] = []
    bar = _progress_bar(len(tasks), progress)
    try:
        if executor is None:
            chunk = _Chunk(named, camera, [], truths, kept, columns)
            target = renderer or process_renderer()
            for task in tasks:
                chunk.tasks = [task]
                rows.extend(_run_chunk(chunk, target))
                if bar is not None:
                    bar.update(1)
        else:
            if renderer is not None:
                raise ParameterError("renderer= is for in-process sweeps; executor workers build their own")
            dask = _dask_client(executor)
            client, options = dask if dask is not None else (None, {})
            size = chunksize or max(1, math.ceil(len(tasks) / (2 * _worker_count(executor, client))))
            starts = range(0, len(tasks), size)
            if client is not None:
                from distributed import as_completed

                # Scenes and truths once for the whole sweep; each chunk names them.
                shared = client.scatter(_Shared(named, truths), hash=False, **{k: v for k, v in options.items() if k == "workers"})
                options = {"pure": False, **options}
                futures = [
                    client.submit(_run_shared_chunk, _Chunk({}, camera, tasks[i : i + size], {}, kept, columns), shared, **options)
                    for i in starts
                ]
                completed: Any = as_completed(futures)
            else:
                futures = [
                    executor.submit(_run_chunk, _Chunk(named, camera, tasks[i : i + size], truths, kept, columns)) for i in starts
                ]
                completed = concurrent.futures.as_completed(futures)
            try:
                for future in completed:
                    done = future.result()
                    rows.extend(done)
                    if bar is not None:
                        bar.update(len(done))
            except BaseException:
                for future in futures:
                    future.cancel()
                raise
    finally:
        if bar is not None:
            bar.close()
    rows.sort(key=lambda r: r[0]["config"])
    frame = pd.DataFrame([r[0] for r in rows])
    if kept:
        frame["images"] = [r[1] for r in rows]
    return frame

"""Penumbra: a headless soft-shadow render service.

Build a :class:`Scene` from numpy arrays or trimesh meshes (or take one from
:mod:`penumbra.scenes`), render it with a :class:`Renderer` and a method
name, and get linear float32 numpy arrays, per-pass timings and statistics back.
:func:`sweep` renders grids of parameters into a pandas DataFrame.
"""

import os
import stat
import tempfile
from typing import Any


def _private_runtime_dir() -> None:
    """Gives Mesa's Vulkan drivers a runtime directory when the environment
    has none, so they do not print "XDG_RUNTIME_DIR is invalid or not set"
    when the first renderer starts (the CLI, ``import penumbra`` in a script
    or a notebook). A variable that is set, even to a bad path, is left
    alone; an empty one counts as unset. The directory is private to the
    user (mode 0700): ``$TMPDIR/penumbra-runtime-<uid>``, reused while it is
    ours and 0700, else a fresh ``mkdtemp``. Runs before the core is loaded,
    so the drivers see it."""
    if os.environ.get("XDG_RUNTIME_DIR") or not hasattr(os, "getuid"):
        return
    path = os.path.join(tempfile.gettempdir(), f"penumbra-runtime-{os.getuid()}")
    try:
        os.mkdir(path, 0o700)
    except FileExistsError:
        pass
    except OSError:
        return
    try:
        info = os.lstat(path)
        usable = stat.S_ISDIR(info.st_mode) and info.st_uid == os.getuid() and stat.S_IMODE(info.st_mode) == 0o700
        if not usable:
            path = tempfile.mkdtemp(prefix="penumbra-runtime-")
    except OSError:
        return
    os.environ["XDG_RUNTIME_DIR"] = path


_private_runtime_dir()

# Imports after the runtime directory is set: the core may start Vulkan.
from penumbra import errors, metrics, scenes
from penumbra._core import __version__
from penumbra.errors import *  # noqa: F403 (the exception hierarchy: penumbra.errors.__all__)
from penumbra.render import MethodInfo, Param, Renderer, RenderResult, adapter_info, method_info, methods, write_image
from penumbra.scene import Camera, Mesh, Scene, SphereLight
from penumbra.sweep import sweep

__all__ = [
    "__version__",
    "errors",
    "scenes",
    "metrics",
    "compare",
    "sweep",
    "Renderer",
    "RenderResult",
    "adapter_info",
    "methods",
    "method_info",
    "MethodInfo",
    "Param",
    "write_image",
    "Camera",
    "Mesh",
    "Scene",
    "SphereLight",
]
__all__ += errors.__all__


def compare(*args: Any, **kwargs: Any) -> Any:
    """Renders a method and Mitsuba ground truth of the same scene and measures
    the difference; see :func:`penumbra.comparison.compare`. (Imported lazily:
    Mitsuba is only needed here.)"""
    from penumbra.comparison import compare as _compare

    return _compare(*args, **kwargs)

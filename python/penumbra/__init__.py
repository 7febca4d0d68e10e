"""Penumbra: a headless soft-shadow render service.

Build a :class:`Scene` from numpy arrays or trimesh meshes (or take one from
:mod:`penumbra.scenes`), render it with a :class:`Renderer` and a method
name, and get linear float32 numpy arrays, per-pass timings and statistics back.
:func:`sweep` renders grids of parameters into a pandas DataFrame.
"""

from typing import Any

from penumbra import errors, metrics, scenes
from penumbra._core import __version__
from penumbra.errors import (
    CameraError,
    GpuError,
    GpuFeatureError,
    GpuUnavailableError,
    GroundTruthError,
    InvalidInputError,
    LightError,
    MeshError,
    ParameterError,
    PenumbraError,
    PenumbraIOError,
    SceneError,
)
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
    "PenumbraError",
    "InvalidInputError",
    "MeshError",
    "LightError",
    "CameraError",
    "SceneError",
    "ParameterError",
    "GpuUnavailableError",
    "GpuError",
    "GpuFeatureError",
    "PenumbraIOError",
    "GroundTruthError",
]


def compare(*args: Any, **kwargs: Any) -> Any:
    """Renders a method and Mitsuba ground truth of the same scene and measures
    the difference; see :func:`penumbra.comparison.compare`. (Imported lazily:
    Mitsuba is only needed here.)"""
    from penumbra.comparison import compare as _compare

    return _compare(*args, **kwargs)

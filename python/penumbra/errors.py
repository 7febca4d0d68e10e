"""The exception hierarchy. Every error Penumbra raises is a :class:`PenumbraError`;
errors in what the caller passed in are also :class:`ValueError` (through
:class:`InvalidInputError`), so ``except ValueError`` catches them too.

The compiled core raises these same classes (``penumbra._core`` imports them).
"""

from __future__ import annotations

__all__ = [
    "PenumbraError",
    "InvalidInputError",
    "MeshError",
    "LightError",
    "CameraError",
    "SceneError",
    "ParameterError",
    "GpuUnavailableError",
    "GpuFeatureError",
    "GpuError",
    "PenumbraIOError",
    "GroundTruthError",
    "InternalError",
]


class PenumbraError(Exception):
    """Base class of every Penumbra error."""


class InvalidInputError(PenumbraError, ValueError):
    """Something the caller passed in is malformed; the message names it."""


class MeshError(InvalidInputError):
    """A mesh is malformed: wrong dtype or shape, NaN/Inf, indices out of range,
    empty or degenerate, or a mesh file that cannot be read."""


class LightError(InvalidInputError):
    """The light is malformed (negative or non-finite radius, bad radiance)."""


class CameraError(InvalidInputError):
    """The camera is malformed (zero-size or huge image, degenerate look-at, bad fov)."""


class SceneError(InvalidInputError):
    """The scene as a whole cannot be rendered (no meshes, light touching or
    surrounded by geometry)."""


class ParameterError(InvalidInputError):
    """Unknown method or parameter, wrong type, or value out of range."""


class GpuUnavailableError(PenumbraError, RuntimeError):
    """No GPU adapter (hardware or software) could be found or opened. The
    message names the driver package to install."""


class GpuFeatureError(GpuUnavailableError):
    """The adapter lacks a feature the method needs: ray queries
    (``EXPERIMENTAL_RAY_QUERY``, Vulkan ``VK_KHR_ray_query``) for ``raytraced``.
    The message names the feature and the adapter; ``penumbra info`` shows
    whether ray queries are available (``ray_queries``)."""


class GpuError(PenumbraError, RuntimeError):
    """The GPU failed while rendering (out of memory, device lost, validation)."""


class PenumbraIOError(PenumbraError, OSError):
    """Writing an output file failed."""


class GroundTruthError(PenumbraError, RuntimeError):
    """Mitsuba ground truth cannot be rendered (Mitsuba missing, no usable
    variant for the requested images, or the export refused)."""


class InternalError(PenumbraError, RuntimeError):
    """Penumbra broke one of its own invariants (for example, an image whose
    shape does not match its pixels): a bug to report, not a problem of the
    input or the GPU."""

"""The width of a shadow's visibility transition, measured on a horizontal
receiver in world units: how contact hardening is quantified (the penumbra
of a caster standing on the receiver widens with the distance from the
contact, Fernando 2005).

The shadow of a vertical edge standing on the ground at ``corner``, from a
light whose foot (the light centre projected on the ground) is ``foot``, is
the ray from ``corner`` away from ``foot``. At distance t along that ray,
the transition width is the world area of the receiver's pixels whose
visibility is strictly between ``low`` and ``high``, within ``window`` of the
ray and ``half_band`` of t, divided by the band's length ``2 half_band``.
Pixel areas come from the world positions of neighbouring pixels, so the
measure does not depend on the camera.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from penumbra.scene import Scene, world_geometry

__all__ = ["standing_edges", "transition_width", "contact_widths", "DISTANCES"]

#: The distances from the contact of :func:`contact_widths` (world units).
DISTANCES = (0.15, 0.35, 0.55, 0.75)


def standing_edges(scene: Scene, mesh: int) -> tuple[np.ndarray, list[np.ndarray]]:
    """The light's foot (x, z) and the ground corners (x, z) of the two
    vertical silhouette edges of a box-like caster ``scene.meshes[mesh]``
    standing on y = 0: the base corners seen from the foot at the extreme angles."""
    vertices = world_geometry(scene.meshes[mesh]).vertices
    base = vertices[np.abs(vertices[:, 1]) < 1e-4][:, [0, 2]]
    foot = np.asarray(scene.light.center, dtype=np.float64)[[0, 2]]
    angle = np.arctan2(base[:, 1] - foot[1], base[:, 0] - foot[0])
    # The casters here lie on one side of the foot: no wrap-around at +-pi.
    return foot, [base[int(np.argmin(angle))], base[int(np.argmax(angle))]]


def transition_width(
    visibility: np.ndarray,
    position: np.ndarray,
    receiver: np.ndarray,
    foot: np.ndarray,
    corner: np.ndarray,
    distances: Sequence[float],
    *,
    half_band: float = 0.1,
    window: float = 0.6,
    low: float = 0.1,
    high: float = 0.9,
) -> list[float]:
    """Transition widths (world units) across the shadow ray of the edge at
    ``corner``, at each of ``distances`` from the corner; ``receiver`` masks
    the horizontal receiver's pixels."""
    p = np.asarray(position, dtype=np.float64)[..., [0, 2]]
    dx, dy = np.gradient(p, axis=1), np.gradient(p, axis=0)
    area = np.abs(dx[..., 0] * dy[..., 1] - dx[..., 1] * dy[..., 0])
    d = (corner - foot) / np.linalg.norm(corner - foot)
    along = (p - corner) @ d
    across = (p - corner) @ np.array([-d[1], d[0]])
    moving = receiver & (visibility > low) & (visibility < high) & (np.abs(across) < window)
    return [float(area[moving & (np.abs(along - t) < half_band)].sum() / (2 * half_band)) for t in distances]


def contact_widths(result: Any, scene: Scene) -> dict[str, float]:
    """``width_t<t>_edge<k>``: the transition widths at :data:`DISTANCES`
    across the shadows of the two standing edges of ``scene.meshes[1]`` on
    the ground (mesh 0), from a render with positions: ``penumbra bench``'s
    ``columns = ["penumbra.transition:contact_widths"]``."""
    foot, corners = standing_edges(scene, 1)
    out = {}
    for k, corner in enumerate(corners, 1):
        widths = transition_width(result.visibility, result.position, result.object_id == 0, foot, corner, DISTANCES)
        out.update({f"width_t{t:g}_edge{k}": w for t, w in zip(DISTANCES, widths)})
    return out

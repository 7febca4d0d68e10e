"""The map bound's margin (passes/map_rays.wgsl, `map_margin`): how far the
fraction of n Vogel-spiral points on the lit side of a straight line may
lie from the lit area of the disk. pvm's and wedges' map bound moves their
visibility only by more than this, so that a lone straight edge, whose
light Eq. 4.1 and the wedges' coverage give exactly, keeps it
(tests/test_pvm.py's straight-edge tests check the images)."""

from __future__ import annotations

import numpy as np
import pytest

GOLDEN_ANGLE = 2.3999632  # as the shader's


def spiral(n: int) -> np.ndarray:
    """The shader's points: equal-area Vogel spiral on the unit disk."""
    i = np.arange(n)
    radius = np.sqrt((i + 0.5) / n)
    return np.stack([radius * np.cos(i * GOLDEN_ANGLE), radius * np.sin(i * GOLDEN_ANGLE)], 1)


def straight_edge_discrepancy(n: int, directions: int = 1440) -> float:
    """The largest |points' lit fraction - lit area fraction| over lines
    through the unit disk: per direction, at offsets just either side of
    every point's projection (where the count jumps) and at the rim."""
    points = spiral(n)
    worst = 0.0
    for theta in np.linspace(0.0, 2.0 * np.pi, directions, endpoint=False):
        proj = points @ np.array([np.cos(theta), np.sin(theta)])
        offsets = np.clip(np.concatenate([proj - 1e-7, proj + 1e-7, [-1.0, 1.0]]), -1.0, 1.0)
        lit_points = (proj[None, :] > offsets[:, None]).mean(1)
        lit_area = (np.arccos(offsets) - offsets * np.sqrt(1.0 - offsets**2)) / np.pi
        worst = max(worst, float(np.abs(lit_points - lit_area).max()))
    return worst


def map_margin(n: int) -> float:
    return 1.2 * n**-0.7  # map_rays.wgsl's


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 6, 8, 12, 16, 24, 32, 48, 64, 100, 128, 192, 256])
def test_the_margin_covers_the_points_error_under_a_straight_edge(n: int) -> None:
    got = straight_edge_discrepancy(n, directions=720 if n > 64 else 1440)
    assert got <= map_margin(n), (n, got, map_margin(n))


def test_the_margin_is_not_far_above_the_error() -> None:
    """It is the error's envelope, not a loose bound: within 1.3x of it at 16."""
    assert map_margin(16) < 1.3 * straight_edge_discrepancy(16)

"""Error metrics against ground truth (SPEC section 6).

All take linear float images. :func:`compare_images` returns every metric as
a dict; given a ground truth rendered with a second seed, it also reports the
ground truth's own noise beside each error (keys ``noise_<metric>``), so an
error below its noise floor reads as such.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from penumbra.errors import ParameterError

if TYPE_CHECKING:
    from penumbra.mitsuba import GroundTruth
    from penumbra.render import RenderResult

__all__ = [
    "PENUMBRA_LOW",
    "PENUMBRA_HIGH",
    "penumbra_region",
    "penumbra_halves",
    "stray_pixels",
    "silhouette_band",
    "lit_mean",
    "rmse",
    "mae",
    "seed_noise",
    "own_noise",
    "flip",
    "compare_images",
    "compare",
]

# Pixels whose ground-truth visibility lies strictly between these are "penumbra".
PENUMBRA_LOW, PENUMBRA_HIGH = 0.02, 0.98


def _same_shape(a: np.ndarray, b: np.ndarray, what: str) -> None:
    if a.shape != b.shape:
        raise ParameterError(f"{what}: shapes differ, {a.shape} against {b.shape}")


def penumbra_region(gt_visibility: np.ndarray) -> np.ndarray:
    """Pixels whose ground-truth visibility is strictly inside (0.02, 0.98)."""
    return (gt_visibility > PENUMBRA_LOW) & (gt_visibility < PENUMBRA_HIGH)


def penumbra_halves(gt_visibility: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The penumbra region split at half visibility: the inner half (ground
    truth in (0.02, 0.5), mostly where the light's centre is hidden, next to
    the umbra) and the outer half ([0.5, 0.98), next to the lit side). A method
    that reasons from the centre's hard shadow decides the two differently
    (pvm: its inner penumbra is 4.2's half-plane, the outer its edge loop)."""
    region = penumbra_region(gt_visibility)
    inner = region & (gt_visibility < 0.5)
    return inner, region & ~inner


def stray_pixels(visibility: np.ndarray, gt_visibility: np.ndarray, geometry: np.ndarray | None = None) -> tuple[int, int]:
    """Pixels a method gets grossly wrong outside the penumbra, and how many
    could be: those fully lit in truth (visibility >= 0.98) that the method
    darkens below 0.5, plus those in the umbra in truth (<= 0.02) that it
    lights above 0.5; over the pixels fully lit or in umbra in truth (within
    ``geometry``, e.g. ``object_id >= 0``, when given). Returns (stray, out of)."""
    _same_shape(visibility, gt_visibility, "visibility")
    v = np.asarray(visibility)
    lit = gt_visibility >= PENUMBRA_HIGH
    umbra = gt_visibility <= PENUMBRA_LOW
    if geometry is not None:
        lit &= geometry
        umbra &= geometry
    stray = (lit & (v < 0.5)) | (umbra & (v > 0.5))
    return int(stray.sum()), int((lit | umbra).sum())


def silhouette_band(object_id: np.ndarray) -> np.ndarray:
    """Pixels within one pixel of a change of object id (geometric silhouettes).
    Penumbra samples each pixel at its centre while Mitsuba's box filter
    averages the pixel, so radiance differs there for reasons unrelated to shadows."""
    from penumbra.raycast import outline_band

    ids = np.asarray(object_id)
    band = np.zeros(ids.shape, dtype=bool)
    for value in np.unique(ids):
        band |= outline_band(ids == value)
    return band


def lit_mean(gt_radiance: np.ndarray, gt_visibility: np.ndarray) -> float:
    """Mean ground-truth radiance over fully lit pixels (visibility >= 0.98),
    the scale that makes radiance errors relative; the mean over all lit
    pixels when none is fully lit."""
    value = gt_radiance.mean(axis=-1) if gt_radiance.ndim == 3 else gt_radiance
    for mask in (gt_visibility >= PENUMBRA_HIGH, value > 0):
        if mask.any():
            return float(value[mask].mean())
    return math.nan


def rmse(a: np.ndarray, b: np.ndarray, mask: np.ndarray | None = None) -> float:
    d = np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64)
    if mask is not None:
        d = d[mask]
    return float(np.sqrt(np.mean(d * d))) if d.size else math.nan


def seed_noise(a: np.ndarray, b: np.ndarray, mask: np.ndarray | None = None) -> float:
    """The noise of one of two estimates that differ only in their seed (two
    ground truths, two renders of a sampling method): their RMSE over
    ``mask`` divided by sqrt(2), since independent noise adds in quadrature.
    The one place the benchmarks and the ``noise_<metric>`` keys take it from."""
    return rmse(a, b, mask) / math.sqrt(2)


def own_noise(
    visibility: tuple[np.ndarray, np.ndarray],
    gt: "GroundTruth",
    *,
    radiance: tuple[np.ndarray, np.ndarray] | None = None,
    object_id: np.ndarray | None = None,
) -> dict[str, float]:
    """A sampling estimate's own noise, from two renders that differ only in
    their seed (:func:`seed_noise`): ``visibility_rmse`` over all pixels,
    ``visibility_rmse_penumbra`` over the ground truth's penumbra region and,
    with ``radiance``, ``radiance_rmse_rel`` relative to the ground truth's
    :func:`lit_mean` off silhouettes (``object_id`` gives them): the
    ``noise_<metric>`` of ground truth, for a method or a peer."""
    gv = gt.images["visibility"]
    out = {"visibility_rmse": seed_noise(*visibility), "visibility_rmse_penumbra": seed_noise(*visibility, penumbra_region(gv))}
    if radiance is not None and "radiance" in gt.images:
        keep = ~silhouette_band(object_id) if object_id is not None else np.ones(gv.shape, dtype=bool)
        out["radiance_rmse_rel"] = seed_noise(*radiance, keep) / lit_mean(gt.images["radiance"], gv)
    return out


def mae(a: np.ndarray, b: np.ndarray, mask: np.ndarray | None = None) -> float:
    d = np.abs(np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64))
    if mask is not None:
        d = d[mask]
    return float(d.mean()) if d.size else math.nan


def flip(test: np.ndarray, reference: np.ndarray) -> float:
    """Mean FLIP (LDR) of a [0, 1] grey image against a reference (``flip-evaluator``)."""
    import flip_evaluator

    def rgb(x: np.ndarray) -> np.ndarray:
        x = np.clip(np.asarray(x, dtype=np.float32), 0, 1)
        return np.ascontiguousarray(np.repeat(x[..., None], 3, axis=-1) if x.ndim == 2 else x)

    _, mean_error, _ = flip_evaluator.evaluate(rgb(reference), rgb(test), "LDR", applyMagma=False)
    return float(mean_error)


def _metrics(radiance: np.ndarray | None, visibility: np.ndarray, object_id: np.ndarray | None, gt: dict[str, np.ndarray]) -> dict[str, float]:
    gv = gt["visibility"]
    _same_shape(visibility, gv, "visibility")
    region = penumbra_region(gv)
    inner, outer = penumbra_halves(gv)
    out: dict[str, float] = {
        "visibility_rmse": rmse(visibility, gv),
        "visibility_rmse_penumbra": rmse(visibility, gv, region),
        # NaN where the half holds no pixel.
        "visibility_rmse_inner": rmse(visibility, gv, inner),
        "visibility_rmse_outer": rmse(visibility, gv, outer),
        "visibility_max_error": float(np.abs(visibility.astype(np.float64) - gv).max()),
        "visibility_flip": flip(visibility, gv),
        "penumbra_pixels": float(region.sum()),
        "penumbra_inner_pixels": float(inner.sum()),
    }
    stray, out_of = stray_pixels(visibility, gv, None if object_id is None else object_id >= 0)
    # Over the pixels fully lit or in umbra; none (an all-penumbra image) counts as no stray pixel.
    out["stray_fraction"] = stray / out_of if out_of else 0.0
    if radiance is not None and "radiance" in gt:
        gr = gt["radiance"]
        _same_shape(radiance, gr, "radiance")
        scale = lit_mean(gr, gv)
        keep = ~silhouette_band(object_id) if object_id is not None else np.ones(gv.shape, dtype=bool)
        out["radiance_rmse_rel"] = rmse(radiance, gr, keep) / scale
        out["radiance_mae_rel"] = mae(radiance, gr, keep) / scale
        out["silhouette_pixels_excluded"] = float((~keep).sum())
    return out


# Metrics whose seed-to-seed value is divided by sqrt(2) to give one ground
# truth's noise (independent noise adds in quadrature).
_QUADRATURE = {"visibility_rmse", "visibility_rmse_penumbra", "visibility_rmse_inner", "visibility_rmse_outer", "radiance_rmse_rel", "radiance_mae_rel"}
_COUNTS = {"penumbra_pixels", "penumbra_inner_pixels", "silhouette_pixels_excluded", "stray_fraction"}


def compare_images(
    visibility: np.ndarray,
    gt: "GroundTruth",
    *,
    radiance: np.ndarray | None = None,
    object_id: np.ndarray | None = None,
) -> dict[str, float]:
    """Every metric of a method's images against ground truth ``gt``:

    - ``visibility_rmse`` over all pixels, ``visibility_rmse_penumbra`` over the
      penumbra region, ``visibility_rmse_inner`` and ``visibility_rmse_outer``
      over its halves (:func:`penumbra_halves`; NaN where a half is empty),
      ``visibility_max_error``, ``visibility_flip`` (mean LDR FLIP);
    - ``stray_fraction``: :func:`stray_pixels` over the pixels it counts
      (on geometry when ``object_id`` is given);
    - ``radiance_rmse_rel`` and ``radiance_mae_rel``, relative to :func:`lit_mean`,
      over pixels off geometric silhouettes (``object_id`` gives them);
    - ``noise_<metric>`` for each, when ``gt.second`` exists: the same metric
      between the two seeds' ground truths, divided by sqrt(2) for RMSE and MAE
      (one ground truth's noise), as is for max error and FLIP.
    """
    out = _metrics(radiance, visibility, object_id, gt.images)
    if gt.second is not None:
        second = gt.second.images
        noise = _metrics(second.get("radiance") if radiance is not None else None, second["visibility"], object_id, gt.images)
        for key, value in noise.items():
            if key not in _COUNTS:
                out[f"noise_{key}"] = value / math.sqrt(2) if key in _QUADRATURE else value
    return out


def compare(result: "RenderResult", gt: "GroundTruth") -> dict[str, float]:
    """:func:`compare_images` of a render result."""
    return compare_images(result.visibility, gt, radiance=result.radiance if "radiance" in gt.images else None, object_id=result.object_id)


def summary(metrics: dict[str, Any]) -> str:
    """The metrics as aligned text lines, each error beside its noise floor."""
    lines = []
    for key, value in metrics.items():
        if key.startswith("noise_"):
            continue
        noise = metrics.get(f"noise_{key}")
        text = f"{key:28s} {value:10.5f}" if key not in _COUNTS else f"{key:28s} {int(value):10d}"
        if noise is not None:
            text += f"   (ground-truth noise {noise:.5f})"
        lines.append(text)
    return "\n".join(lines)

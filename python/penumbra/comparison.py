"""Render a method and ground truth of the same scene (Mitsuba, or the
engine's ``raytraced`` at a high sample count), measure, and draw them side
by side: ``penumbra.compare(...)`` and ``penumbra compare``."""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from penumbra import metrics as metrics_module
from penumbra.errors import ParameterError, SceneError
from penumbra.mitsuba import GroundTruth, ground_truth
from penumbra.render import Renderer, RenderResult
from penumbra.scene import Camera, Scene

__all__ = ["Comparison", "compare", "comparison_figure"]


@dataclass
class Comparison:
    result: RenderResult
    ground_truth: GroundTruth
    metrics: dict[str, float]

    def save_figure(self, path: str | os.PathLike[str]) -> None:
        comparison_figure(self, path)


def compare(
    scene: Scene,
    method: str = "hard",
    *,
    camera: Camera | None = None,
    renderer: Renderer | None = None,
    spp: int = 256,
    seed: int = 0,
    noise_seed: int | None = 1,
    cache_dir: str | os.PathLike[str] | None = None,
    out: str | os.PathLike[str] | None = None,
    truth: str = "mitsuba",
    **params: Any,
) -> Comparison:
    """Renders ``scene`` with ``method`` (and its ``params``) and the ground
    truth (radiance and visibility at ``spp`` samples per pixel; with
    ``noise_seed`` a second ground truth for the noise floor), computes every
    metric of :mod:`penumbra.metrics`, and writes the side-by-side picture to
    ``out`` when given.

    ``truth``: ``"mitsuba"`` (the independent default, cached under
    ``cache_dir``) or ``"raytraced"``: the engine's own method ``raytraced`` at
    ``spp`` light samples (:func:`penumbra.truth.raytraced_truth`; give it
    thousands: 4096 for a noise floor near Mitsuba's at 1024), not cached."""
    from penumbra.truth import TRUTHS, raytraced_truth

    if not isinstance(scene, Scene):
        raise SceneError(f"expected a penumbra.Scene, got {type(scene).__name__}")
    if truth not in TRUTHS:
        raise ParameterError(f"truth must be one of {list(TRUTHS)}, got {truth!r}")
    renderer = renderer or Renderer()
    result = renderer.render(scene, method, camera=camera, **params)
    if truth == "raytraced":
        gt = raytraced_truth(scene, camera, n_samples=spp, seed=seed, noise_seed=noise_seed, renderer=renderer)
    else:
        gt = ground_truth(scene, camera, spp=spp, seed=seed, noise_seed=noise_seed, cache_dir=cache_dir)
    comparison = Comparison(result, gt, metrics_module.compare(result, gt))
    if out is not None:
        comparison.save_figure(out)
    return comparison


def _srgb(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0, 1)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def comparison_figure(c: Comparison, path: str | os.PathLike[str]) -> None:
    """One PNG: the method's radiance, Mitsuba's, and the visibility error
    (method minus ground truth) colour-mapped with its scale, metrics beneath."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    r, g = c.result.radiance, c.ground_truth.radiance
    exposure = 1.0 / max(float(np.percentile(g, 99.5)), 1e-12)
    diff = c.result.visibility.astype(np.float64) - c.ground_truth.visibility
    limit = max(float(np.abs(diff).max()), 1e-3)
    h, w = r.shape[:2]
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.6 * h / w + 1.0), constrained_layout=True)
    params = ", ".join(f"{k}={v}" for k, v in c.result.params.items())
    axes[0].imshow(_srgb(r * exposure))
    axes[0].set_title(f"penumbra: {c.result.method}\n{c.result.total_ms:.0f} ms", fontsize=9)
    axes[1].imshow(_srgb(g * exposure))
    gt_seconds = sum(c.ground_truth.seconds.values())
    truth = "penumbra raytraced" if c.ground_truth.variant == "raytraced" else f"Mitsuba 3 ({c.ground_truth.variant}"
    truth = f"{truth}, {c.ground_truth.spp} spp)" if c.ground_truth.variant != "raytraced" else f"{truth} ({c.ground_truth.spp} samples)"
    axes[1].set_title(f"{truth}\n{gt_seconds:.1f} s", fontsize=9)
    image = axes[2].imshow(diff, cmap="RdBu_r", vmin=-limit, vmax=limit)
    axes[2].set_title("visibility error (method - ground truth)\nred: too lit, blue: too dark", fontsize=9)
    fig.colorbar(image, ax=axes[2], shrink=0.8, label="visibility difference")
    for ax in axes:
        ax.set_xticks([])
        ax.set_yticks([])
    m = c.metrics
    text = (
        f"{params}\n"
        f"visibility RMSE {m['visibility_rmse']:.4f} (noise {m.get('noise_visibility_rmse', float('nan')):.4f}), "
        f"penumbra {m['visibility_rmse_penumbra']:.4f} (noise {m.get('noise_visibility_rmse_penumbra', float('nan')):.4f}), "
        f"max {m['visibility_max_error']:.3f}, FLIP {m['visibility_flip']:.4f}; "
        f"radiance RMSE {100 * m.get('radiance_rmse_rel', float('nan')):.2f}% of the lit mean"
    )
    fig.supxlabel(text, fontsize=8)
    fig.savefig(path, dpi=100)
    plt.close(fig)

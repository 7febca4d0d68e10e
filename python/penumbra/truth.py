"""In-engine ground truth: method ``raytraced`` at a high sample count, in the
form of Mitsuba's :class:`~penumbra.mitsuba.GroundTruth`, so that
:func:`penumbra.compare`, :func:`penumbra.sweep` and :mod:`penumbra.metrics`
take either.

``raytraced`` traces one shadow ray per light sample of ``reference``'s
sphere sampling and converges to the fraction of the light's solid angle a
point sees, what Mitsuba's visibility measures (its penumbra RMSE against
Mitsuba at 1024 samples is within 1.31 times the two estimators' noise on every
built-in and real-mesh scene: ``penumbra bench --config benchmarks/raytraced_accuracy.toml``). Its noise
floor comes, as Mitsuba's does, from a second render with another seed
(``.second``). Mitsuba stays the independent default: this truth shares the
engine's G-buffer, shading and scene preparation with the methods it
judges, so it cannot catch their common errors.
"""

from __future__ import annotations

from typing import Any

from penumbra.errors import ParameterError
from penumbra.mitsuba import GroundTruth
from penumbra.render import Renderer
from penumbra.scene import Camera, Scene

__all__ = ["TRUTHS", "raytraced_truth"]

#: The ground truths :func:`penumbra.compare` and :func:`penumbra.sweep` can use.
TRUTHS = ("mitsuba", "raytraced")


def raytraced_truth(
    scene: Scene,
    camera: Camera | None = None,
    *,
    n_samples: int = 4096,
    seed: int = 0,
    noise_seed: int | None = 1,
    renderer: Renderer | None = None,
    **params: Any,
) -> GroundTruth:
    """``raytraced`` at ``n_samples`` light samples per pixel (seed ``seed``)
    as a :class:`~penumbra.mitsuba.GroundTruth` (``variant`` ``"raytraced"``):
    its radiance and visibility, and with ``noise_seed`` the same rendered
    with that seed in ``.second`` for the noise floor. ``params`` go to the
    method (``ray_offset``; not ``adaptive``: a truth takes every ray)."""
    if noise_seed is not None and noise_seed == seed:
        raise ParameterError("noise_seed must differ from seed")
    if params.get("adaptive"):
        raise ParameterError("a raytraced truth takes the full sample count at every pixel: adaptive must be False")
    renderer = renderer or Renderer()
    result = renderer.render(scene, "raytraced", camera=camera, n_samples=n_samples, seed=seed, **params)
    second = None
    if noise_seed is not None:
        second = raytraced_truth(scene, camera, n_samples=n_samples, seed=noise_seed, noise_seed=None, renderer=renderer, **params)
    seconds = result.total_ms / 1000.0
    return GroundTruth(
        images={"radiance": result.radiance, "visibility": result.visibility},
        spp=int(result.params["n_samples"]),
        seed=int(seed),
        variant="raytraced",
        # One render makes both images.
        seconds={"render": seconds},
        cached={"render": False},
        second=second,
        extra={"truth": "raytraced", "light_samples": result.stats.get("light_samples"), "params": result.params, "adapter": renderer.adapter_info.get("name")},
    )

"""The numbers of docs/ground_truth.md's export checks, printed.

1. Mitsuba's unshadowed radiance against Penumbra's (relative RMSE, off silhouettes).
2. The visibility estimator against the closed form of a sphere occluder
   (RMSE over the penumbra, beside the estimator's own seed-to-seed noise).
3. Mitsuba's radiance from small sphere lights, exported as spheres, against
   Penumbra's exact irradiance (why small lights are exported as points).

The scenes are those of tests/test_ground_truth.py (`penumbra.scenes.lit_plane`,
`sphere_over_plane`).

    python benchmarks/checks.py
"""

from __future__ import annotations

import numpy as np

import penumbra
from penumbra import metrics
from penumbra import mitsuba as pm
from penumbra.analytic import sphere_over_plane_visibility


def unshadowed_radiance(renderer: penumbra.Renderer) -> None:
    scene = penumbra.scenes.lit_plane()
    result = renderer.render(scene)
    gt = pm.ground_truth(scene, spp=64, kinds=["radiance"], cache=False)
    keep = ~metrics.silhouette_band(result.object_id)
    rel = metrics.rmse(result.radiance, gt.radiance, keep) / metrics.lit_mean(gt.radiance, np.ones(result.visibility.shape))
    print(f"1. unshadowed radiance, Mitsuba against Penumbra: relative RMSE {100 * rel:.3f}%")


def estimator_against_closed_form() -> None:
    scene = penumbra.scenes.sphere_over_plane()
    gt = pm.ground_truth(scene, spp=256, seed=3, noise_seed=4, kinds=["visibility"], cache=False)
    closed, seen = sphere_over_plane_visibility(scene, gt.images["hit_distance"])
    region = seen & metrics.penumbra_region(closed)
    error = metrics.rmse(gt.visibility, closed, region)
    assert gt.second is not None
    noise = metrics.seed_noise(gt.visibility, gt.second.visibility, region)
    print(f"2. visibility estimator against the cap-overlap closed form: RMSE {error:.5f}, its noise {noise:.5f} ({region.sum()} penumbra pixels)")


def small_sphere_lights(renderer: penumbra.Renderer) -> None:
    saved = pm.POINT_LIGHT_RATIO
    pm.POINT_LIGHT_RATIO = 0.0  # export every light as a sphere
    try:
        cells = []
        for r in (0.5, 0.05, 0.01, 0.003, 0.001):
            scene = penumbra.scenes.get(width=48, height=48, light_radius=r)
            result = renderer.render(scene)
            gt = pm.ground_truth(scene, spp=64, cache=False)
            lit = (gt.visibility > 0.999) & (result.visibility == 1) & (result.object_id == 0)
            ratio = float(np.median(gt.radiance[lit][:, 0] / result.radiance[lit][:, 0]))
            cells.append(f"r={r}: {ratio:.4f}")
    finally:
        pm.POINT_LIGHT_RATIO = saved
    print("3. Mitsuba sphere light / exact irradiance, lit ground about 5 units away: " + ", ".join(cells))


def main() -> None:
    renderer = penumbra.Renderer()
    print(f"adapter {renderer.adapter_info['name']}; Mitsuba {pm.variant()}")
    unshadowed_radiance(renderer)
    estimator_against_closed_form()
    small_sphere_lights(renderer)


if __name__ == "__main__":
    main()

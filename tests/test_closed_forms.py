"""Correctness against closed forms (issue 2): the unshadowed radiance of a
plane under the sphere light, the horizon-clipped irradiance of a sphere light,
and the position of a hard shadow."""

from __future__ import annotations

import numpy as np
import pytest

import penumbra
from penumbra.raycast import outline_band, point_light_visibility
from penumbra.scenes import ground_plane, sphere

from penumbra.analytic import plane_hits


def test_unshadowed_plane_radiance_matches_the_point_form(renderer: penumbra.Renderer) -> None:
    # A sphere light fully above the plane: E = pi L (r/D)^2 cos(theta) exactly (SPEC 3, 6).
    light = penumbra.SphereLight((0.7, 3.0, -0.4), 0.5, radiance=(40.0, 25.0, 10.0))
    camera = penumbra.Camera(eye=(1.0, 4.0, 6.0), target=(0.0, 0.0, -0.5), fov_y=50, width=160, height=120)
    albedo = np.array([0.8, 0.6, 0.4])
    scene = penumbra.Scene([penumbra.Mesh(ground_plane().vertices, ground_plane().faces, albedo=albedo)], light, camera)
    result = renderer.render(scene)

    p = plane_hits(camera)
    inside = (np.abs(p[..., 0]) < 4.9) & (np.abs(p[..., 2]) < 4.9)
    assert inside.sum() > 10_000
    assert (result.object_id[inside] == 0).all()
    # The camera model: the G-buffer's positions are where the analytic rays meet the plane.
    np.testing.assert_allclose(result.position[inside], p[inside], atol=2e-4)

    to_light = np.asarray(light.center, dtype=np.float64) - p
    d = np.linalg.norm(to_light, axis=-1)
    cos_theta = to_light[..., 1] / d
    radiance_l = np.asarray(light.radiance, dtype=np.float64)
    irradiance = np.pi * radiance_l * (light.radius / d[..., None]) ** 2 * cos_theta[..., None]
    expected = albedo / np.pi * irradiance
    relative = np.abs(result.radiance[inside] - expected[inside]) / expected[inside]
    assert relative.max() < 1e-3, f"max relative error {relative.max():.2e}"
    assert (result.visibility[inside] == 1.0).all()
    assert (result.radiance[result.object_id < 0] == 0).all()


def cap_irradiance(p: np.ndarray, n: np.ndarray, center: np.ndarray, radius: float, radiance: float, steps: int = 1500) -> float:
    """E = L * integral over the light's cap of max(w.n, 0) dw, by the midpoint
    rule in (cos alpha, phi) around the centre direction: independent of the
    closed form under test."""
    axis = center - p
    dist = np.linalg.norm(axis)
    axis /= dist
    cos_sigma = np.sqrt(1 - (radius / dist) ** 2)
    helper = np.array([1.0, 0, 0]) if abs(axis[0]) < 0.9 else np.array([0, 1.0, 0])
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)
    ca = cos_sigma + (1 - cos_sigma) * (np.arange(steps) + 0.5) / steps
    phi = 2 * np.pi * (np.arange(steps) + 0.5) / steps
    sa = np.sqrt(1 - ca**2)
    w = (ca[:, None, None] * axis + sa[:, None, None] * (np.cos(phi)[None, :, None] * u + np.sin(phi)[None, :, None] * v))
    cosine = np.clip(w @ n, 0, None)
    return radiance * cosine.sum() * (1 - cos_sigma) / steps * 2 * np.pi / steps


def test_irradiance_of_a_light_straddling_the_horizon(renderer: penumbra.Renderer) -> None:
    # A wall in the plane x = 0 facing +x, the light's centre 0.2 in front of that
    # plane with radius 0.5: the sphere crosses the plane (beside the wall, which
    # starts at z = 1), so every wall point sees the light cut by its horizon.
    wall = penumbra.Mesh([[0, -1.5, 1.0], [0, 1.5, 1.0], [0, 1.5, 5], [0, -1.5, 5]], [[0, 1, 2], [0, 2, 3]], albedo=1.0, name="wall")
    light = penumbra.SphereLight((0.2, 0.0, 0.0), 0.5, radiance=10.0)
    camera = penumbra.Camera(eye=(4.0, 0.5, 3.0), target=(0.0, 0.0, 3.0), fov_y=60, width=64, height=64)
    result = renderer.render(penumbra.Scene([wall], light, camera))
    rng = np.random.default_rng(7)
    pixels = np.argwhere(result.object_id == 0)
    assert len(pixels) > 1000
    for i, j in pixels[rng.choice(len(pixels), 25, replace=False)]:
        p = result.position[i, j].astype(np.float64)
        expected = cap_irradiance(p, np.array([1.0, 0, 0]), np.asarray(light.center, float), light.radius, 10.0)
        # Hard visibility is 1 here: the light's centre is in front of the wall.
        got = result.radiance[i, j, 0] * np.pi
        assert got == pytest.approx(expected, rel=1e-3), (i, j, p)


def test_hard_shadow_outline_matches_the_analytic_projection(renderer: penumbra.Renderer) -> None:
    # Radius-0 light: a plane point is in shadow iff its segment to the light
    # meets the sphere. The mesh is a fine icosphere (its deviation from the
    # sphere is ~2e-4 of the radius, far below a pixel).
    center, radius = np.array([0.0, 1.5, 0.0]), 1.0
    light = penumbra.SphereLight((0.5, 5.0, 0.3), 0.0, intensity=30.0)
    camera = penumbra.Camera(eye=(0.0, 7.0, 5.0), target=(0.0, 0.0, 0.0), fov_y=45, width=256, height=256)
    scene = penumbra.Scene([ground_plane(), sphere(tuple(center), radius, subdivisions=5)], light, camera)
    result = renderer.render(scene, map_size=2048)

    p = plane_hits(camera)
    to_light = np.asarray(light.center, float) - p
    length = np.linalg.norm(to_light, axis=-1)
    direction = to_light / length[..., None]
    # Closest approach of the segment to the sphere's centre.
    t = np.clip(((center - p) * direction).sum(-1), 0, length)
    closest = p + t[..., None] * direction
    analytic = np.linalg.norm(closest - center, axis=-1) < radius

    plane = result.object_id == 0
    rendered = result.visibility < 0.5
    assert (analytic & plane).sum() > 2000, "the shadow is in view"
    mismatch = plane & (rendered != analytic)
    near_outline = outline_band(analytic)
    assert not (mismatch & ~near_outline).any(), f"{(mismatch & ~near_outline).sum()} pixels off by more than one pixel"


@pytest.mark.parametrize("name", penumbra.scenes.names())
def test_hard_matches_exact_ray_casting_beyond_the_outline(renderer: penumbra.Renderer, name: str) -> None:
    # With its default bias, `hard` at radius 0 agrees with CPU ray casting of
    # the light's centre everywhere but a one-pixel band along shadow outlines:
    # no acne, no light leaks (the table in docs/methods/hard.md comes from
    # `python benchmarks/point_light.py`, the same comparison at 256x256).
    scene = penumbra.scenes.get(name, width=128, height=128, light_radius=0.0)
    result = renderer.render(scene)
    geometry = result.object_id >= 0
    exact = np.zeros(geometry.shape, dtype=bool)
    exact[geometry] = point_light_visibility(scene, result.position[geometry], result.normal[geometry]) > 0.5
    wrong = geometry & ((result.visibility > 0.5) != exact) & ~outline_band(exact)
    assert not wrong.any(), f"{wrong.sum()} pixels disagree beyond the outline"
    assert (geometry & ~exact).sum() > 0.02 * geometry.sum(), "the scene has shadows to get wrong"


def test_point_light_errors_count_acne_and_leaks_beyond_and_on_the_outline() -> None:
    from types import SimpleNamespace

    from penumbra.raycast import point_light_errors

    exact = np.zeros((6, 6), dtype=bool)
    exact[:, :3] = True  # lit on the left; the outline band is columns 2 and 3
    visibility = exact.astype(np.float32)
    visibility[0, 0] = 0.0  # acne beyond the band
    visibility[5, 2] = 0.0  # acne on it
    visibility[1, 5] = 1.0  # a leak beyond it
    object_id = np.zeros((6, 6), dtype=np.int32)
    object_id[5, 5] = -1  # background: not counted
    visibility[5, 5] = 1.0
    e = point_light_errors(SimpleNamespace(object_id=object_id, visibility=visibility), penumbra.scenes.get(), exact)
    assert e == {"acne": 1.0, "leak": 1.0, "acne_on_outline": 1.0, "leak_on_outline": 0.0, "geometry_pixels": 35.0}


def test_ray_caster_sees_a_blocker() -> None:
    quad = penumbra.Mesh([[-1, 1, -1], [1, 1, -1], [1, 1, 1], [-1, 1, 1]], [[0, 2, 1], [0, 3, 2]])
    scene = penumbra.Scene([quad], penumbra.SphereLight((0, 3, 0), 0.0, intensity=1.0))
    points = np.array([[0.0, 0, 0], [3.0, 0, 0], [0.0, 0, 0]])
    normals = np.array([[0.0, 1, 0], [0.0, 1, 0], [0.0, -1, 0]])
    np.testing.assert_array_equal(point_light_visibility(scene, points, normals), [0.0, 1.0, 0.0])

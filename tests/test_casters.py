"""The light's raster passes leave out triangles that hide no part of the
light from any point of the scene (rust/penumbra-core/src/casters.rs; issue
30): the floor slab under everything, the walls of a room lit from inside.
The Rust unit tests check the geometry; these check what a render reports
and that the pass cache tells the left-out sets apart."""

from __future__ import annotations

import numpy as np
import pytest

import penumbra
from penumbra import scenes
from penumbra.scenes import Scene, SphereLight

SIZE = 48


@pytest.mark.parametrize("method", ["hard", "pcss", "backprojection", "pvmf"])
def test_the_floor_slab_is_left_out_of_the_light_maps(renderer: penumbra.Renderer, method: str) -> None:
    scene = scenes.get("sphere_on_plane", width=SIZE, height=SIZE)
    result = renderer.render(scene, method, outputs=["visibility"])
    # The slab is convex and under the sphere and the light: its 12 faces
    # shade nothing. The sphere's faces (smooth, not convex-checked) stay.
    assert result.stats["non_casters"] == 12
    assert np.isfinite(result.visibility).all()


def test_a_room_lit_from_inside_draws_none_of_its_walls(renderer: penumbra.Renderer) -> None:
    room = scenes.inverted_box((0.0, 2.0, 0.0), (6.0, 4.0, 6.0))
    pillar = scenes.box((1.0, 1.0, 0.5), (0.6, 2.0, 0.6), name="pillar", object_id=1)
    camera = scenes.Camera(eye=(-2.5, 2.0, -2.5), target=(1.0, 1.0, 1.0), fov_y=70.0, width=SIZE, height=SIZE)
    scene = Scene([room, pillar], SphereLight(center=(0.0, 3.0, 0.0), radius=0.3, intensity=20.0), camera)
    result = renderer.render(scene, "hard", outputs=["visibility"])
    # The room's 12 faces, and the pillar's bottom (on the floor's plane).
    assert result.stats["non_casters"] == 12 + 2
    # With the walls out, the map's frustum need only cover the pillar and
    # its penumbra (issue 30): one map, not the cube's faces.
    assert result.stats["cube_map"] == 0
    cube = renderer.render(scene, "hard", outputs=["visibility"], projection="cube")
    assert (np.abs(cube.visibility - result.visibility) > 0.5).mean() < 0.002


def test_the_pass_cache_redraws_the_map_when_the_radius_changes_what_is_left_out() -> None:
    """The slab's side at x = 5 passes 0.6 from the light's centre: left out
    under a light of radius 0.3, drawn under one of 0.8. A cached map drawn
    without it must not serve the larger light."""
    scene = scenes.get("sphere_on_plane", width=SIZE, height=SIZE)
    cached = penumbra.Renderer(pass_cache=True)
    counts = []
    for radius in (0.3, 0.8):
        lit = Scene(scene.meshes, SphereLight(center=(4.4, 3.0, 0.0), radius=radius, intensity=40.0), scene.camera)
        result = cached.render(lit, "hard", outputs=["visibility"])
        fresh = penumbra.Renderer(pass_cache=False).render(lit, "hard", outputs=["visibility"])
        counts.append(result.stats["non_casters"])
        assert result.stats["reused_shadow_map"] == 0
        np.testing.assert_array_equal(result.visibility, fresh.visibility)
    assert counts == [12, 10]

"""The renderer service: built-in scenes, outputs, timings, threads, files."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest
import trimesh

import penumbra

SIZE = 96


@pytest.mark.parametrize("name", penumbra.scenes.names())
def test_builtin_scene_renders_with_a_visible_shadow(renderer: penumbra.Renderer, name: str) -> None:
    scene = penumbra.scenes.get(name, width=SIZE, height=SIZE)
    renderer.clear_pass_cache()  # the shadow map is rendered, not reused
    result = renderer.render(scene)
    for key, image in result.images.items():
        assert np.isfinite(image).all(), key
    assert result.radiance.shape == (SIZE, SIZE, 3) and result.radiance.dtype == np.float32
    assert result.object_id.dtype == np.int32
    ground = result.object_id == 0
    shadowed = ground & (result.visibility == 0)
    lit = ground & (result.visibility == 1)
    assert shadowed.sum() > 0.01 * ground.sum(), "a shadow on the ground"
    assert lit.sum() > 0.5 * ground.sum(), "most of the ground is lit"
    assert set(np.unique(result.visibility)) <= {0.0, 1.0}, "hard shadows are binary"
    # Shadowed ground is darker than lit ground, and background is black and marked -1.
    assert result.radiance[shadowed].max() == 0.0 and result.radiance[lit].min() > 0.0
    assert (result.radiance[result.object_id == -1] == 0).all()
    assert set(np.unique(result.object_id)) == {-1} | {m.object_id for m in scene.meshes}
    # Normals are unit length where there is geometry.
    n = np.linalg.norm(result.normal[~(result.object_id == -1)], axis=-1)
    np.testing.assert_allclose(n, 1.0, atol=1e-5)
    assert result.stats["triangles"] == sum(len(m.faces) for m in scene.meshes)
    assert result.stats["shadow_maps_rendered"] == 1


def test_scene_names_and_default() -> None:
    names = penumbra.scenes.names()
    assert names[0] == penumbra.scenes.DEFAULT == "sphere_on_plane"
    assert {"sphere_on_plane", "cube_on_plane", "overlapping_casters", "resting_box"} <= set(names)


def test_resting_box_touches_the_ground() -> None:
    scene = penumbra.scenes.get("resting_box")
    box = scene.meshes[1]
    world = (box.transform[:3, :3] @ box.vertices.T).T + box.transform[:3, 3]
    assert abs(world[:, 1].min()) < 1e-6


def test_same_input_same_output(renderer: penumbra.Renderer) -> None:
    scene = penumbra.scenes.get("overlapping_casters", width=SIZE, height=SIZE)
    a, b = renderer.render(scene), renderer.render(scene)
    for key in a.images:
        np.testing.assert_array_equal(a.images[key], b.images[key])


def test_threads_give_the_serial_images(renderer: penumbra.Renderer) -> None:
    scenes = [penumbra.scenes.get(n, width=64, height=48) for n in penumbra.scenes.names()]
    serial = [renderer.render(s).radiance for s in scenes]
    with ThreadPoolExecutor(4) as pool:
        parallel = list(pool.map(lambda s: renderer.render(s).radiance, scenes * 2))
    for i, image in enumerate(parallel):
        np.testing.assert_array_equal(image, serial[i % len(scenes)])


@pytest.mark.parametrize("timing", ["auto", "cpu"])
def test_timings_name_every_pass(timing: str) -> None:
    try:
        renderer = penumbra.Renderer(timing=timing)
    except penumbra.GpuUnavailableError as e:
        pytest.skip(str(e))
    result = renderer.render(penumbra.scenes.get(width=32, height=32))
    assert list(result.timings) == ["gbuffer", "shadow_map", "visibility", "shading", "readback"]
    assert all(t >= 0 for t in result.timings.values())
    expected = "cpu_clock" if timing == "cpu" or not renderer.adapter_info["timestamp_queries"] else "gpu_timestamps"
    assert result.timing_source == renderer.timing_source == expected
    assert result.total_ms > 0


def test_intermediates_and_params_are_reported(renderer: penumbra.Renderer) -> None:
    scene = penumbra.scenes.get(width=32, height=32)
    plain = renderer.render(scene, map_size=256)
    assert "shadow_map" not in plain.images
    full = renderer.render(scene, map_size=256, intermediates=True)
    assert full.images["shadow_map"].shape == (256, 256)
    depth = full.images["shadow_map"]
    assert np.isfinite(depth).all() and depth.min() > 0
    assert full.params == {"map_size": 256, "projection": "auto", "bias": "slope", "normal_offset": 1.0, "constant_bias": 0.5, "slope_bias": 1.0}
    assert full.method == "hard"
    np.testing.assert_array_equal(plain.radiance, full.radiance)


@pytest.mark.parametrize("method", penumbra.methods())
def test_every_method_reads_its_intermediates_back(renderer: penumbra.Renderer, method: str) -> None:
    """Every intermediate image a method exposes can be read back (32 bits
    a channel: `Frame::intermediate` refuses others with an error, where the
    readback used to panic), is finite, and leaves the image unchanged."""
    scene = penumbra.scenes.get(width=32, height=32)
    small = {"map_size": 256} if "map_size" in penumbra.render.method_info(method).defaults() else {}
    plain = renderer.render(scene, method, **small)
    full = renderer.render(scene, method, **small, intermediates=True)
    extra = set(full.images) - set(plain.images)
    for name in extra:
        image = np.asarray(full.images[name])
        assert image.size > 0 and np.isfinite(image).all(), name
    np.testing.assert_array_equal(plain.visibility, full.visibility)


@pytest.mark.parametrize("bias", ["slope", "second_depth"])
def test_bias_schemes_show_no_acne_on_lit_surfaces(renderer: penumbra.Renderer, bias: str) -> None:
    # No pixel whose light centre is above its horizon and unoccluded in the
    # analytic sense may be shadowed. The sphere over the plane: a lit sphere
    # point can only be hidden by the sphere itself, which it is not when it
    # faces the light (convex caster).
    scene = penumbra.scenes.get("sphere_on_plane", width=128, height=128)
    result = renderer.render(scene, bias=bias)
    to_light = np.asarray(scene.light.center) - result.position
    facing = (result.normal * to_light).sum(-1) > 0
    sphere = result.object_id == 1
    assert (result.visibility[sphere & facing] == 1).all()
    raw = renderer.render(scene, bias="none")
    assert (raw.visibility[sphere & facing] == 0).sum() > 100, "the raw comparison does show acne"


def test_mesh_from_trimesh_and_transform(renderer: penumbra.Renderer) -> None:
    box = trimesh.creation.box(extents=(1, 1, 1))
    moved = np.eye(4)
    moved[:3, 3] = (0.5, 1.5, 0.0)
    scene = penumbra.scenes.get(width=48, height=48)
    scene.meshes = [scene.meshes[0], penumbra.Mesh.from_trimesh(box, transform=moved, object_id=7)]
    result = renderer.render(scene)
    assert (result.object_id == 7).any()
    p = result.position[result.object_id == 7]
    assert p[:, 1].min() > 0.99 - 1e-4 and p[:, 0].max() < 1.0 + 1e-4


def test_vertex_normals_shade_smoothly(renderer: penumbra.Renderer) -> None:
    ico = trimesh.creation.icosphere(subdivisions=3)
    scene = penumbra.scenes.get(width=64, height=64)
    flat = renderer.render(scene.__class__([scene.meshes[0], penumbra.Mesh(ico.vertices + (0, 1.6, 0), ico.faces, object_id=1)], scene.light, scene.camera))
    smooth = renderer.render(scene.__class__([scene.meshes[0], penumbra.Mesh(ico.vertices + (0, 1.6, 0), ico.faces, normals=ico.vertices / np.linalg.norm(ico.vertices, axis=1, keepdims=True), object_id=1)], scene.light, scene.camera))
    # Interpolated vertex normals follow the sphere's true normal closely; face
    # normals deviate by up to half a face's angular size.
    def deviation(result: penumbra.RenderResult) -> np.ndarray:
        mask = result.object_id == 1
        true = result.position[mask] - np.array([0.0, 1.6, 0.0])
        true /= np.linalg.norm(true, axis=-1, keepdims=True)
        return np.arccos(np.clip((result.normal[mask] * true).sum(-1), -1, 1))

    assert deviation(smooth).max() < 0.02 < 0.05 < deviation(flat).max()


def test_point_light_is_continuous_with_small_lights(renderer: penumbra.Renderer) -> None:
    scene = penumbra.scenes.get(width=48, height=48)
    point = renderer.render(scene.with_light(scene.light.with_radius(0.0)))
    tiny = renderer.render(scene.with_light(scene.light.with_radius(1e-4)))
    lit = (point.visibility == 1) & (tiny.visibility == 1)
    np.testing.assert_allclose(point.radiance[lit], tiny.radiance[lit], rtol=1e-4)


def test_write_png_exr_npy(renderer: penumbra.Renderer, tmp_path: Path) -> None:
    result = renderer.render(penumbra.scenes.get(width=24, height=16))
    for name in ("a.png", "a.exr", "a.npy"):
        result.save(tmp_path / name)
    assert (tmp_path / "a.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (tmp_path / "a.exr").read_bytes()[:4] == b"\x76\x2f\x31\x01"
    np.testing.assert_array_equal(np.load(tmp_path / "a.npy"), result.radiance)
    result.save(tmp_path / "v.png", image="visibility")
    assert (tmp_path / "v.png").stat().st_size > 0


def test_outputs_read_back_only_what_is_asked(renderer: penumbra.Renderer) -> None:
    """`outputs=` reads back the images named (and shades only for radiance;
    object ids come from their own image, written by the shading pass or
    without radiance by the object-id pass, or from the normals where those
    are read back), with the same pixels as a full render."""
    scene = penumbra.scenes.get(width=32, height=32)
    full = renderer.render(scene, "pcss", map_size=256)
    assert sorted(full.images) == sorted(penumbra.render.IMAGES)
    only = renderer.render(scene, "pcss", map_size=256, outputs=["visibility"])
    assert list(only.images) == ["visibility"] and "shading" not in only.timings and "geometry_pixels" not in only.stats
    np.testing.assert_array_equal(only.visibility, full.visibility)
    some = renderer.render(scene, "pcss", map_size=256, outputs=("object_id", "depth", "radiance"))
    assert sorted(some.images) == ["depth", "object_id", "radiance"] and some.stats["geometry_pixels"] == full.stats["geometry_pixels"]
    for name in some.images:
        np.testing.assert_array_equal(some.images[name], full.images[name])
    # Object ids without radiance or normals: their own pass and image (a
    # quarter of the normals' bytes), the same ids as from the normals.
    ids = renderer.render(scene, "pcss", map_size=256, outputs=["visibility", "object_id"])
    assert "object_ids" in ids.timings and "shading" not in ids.timings and ids.stats["geometry_pixels"] == full.stats["geometry_pixels"]
    np.testing.assert_array_equal(ids.object_id, full.object_id)
    assert "object_ids" not in renderer.render(scene, "pcss", map_size=256, outputs=["object_id", "normal"]).timings
    # Object ids that are not the meshes' indices, through each path: the
    # object-id pass, the shading pass, and the normals.
    renumbered = penumbra.Scene([penumbra.Mesh(m.vertices, m.faces, object_id=9 - 4 * i, name=m.name) for i, m in enumerate(scene.meshes)], scene.light, scene.camera)
    paths = [["visibility", "object_id"], ["radiance", "object_id"], ["object_id", "normal"]]
    got = [renderer.render(renumbered, "hard", map_size=256, outputs=o).object_id for o in paths]
    assert set(np.unique(got[2])) == {-1} | {9 - 4 * i for i in range(len(scene.meshes))}
    for ids in got[:2]:
        np.testing.assert_array_equal(ids, got[2])
    assert renderer.render(scene, "pcss", map_size=256, outputs=[]).images == {}
    with pytest.raises(penumbra.ParameterError, match="no image 'visibility'"):
        some.visibility
    with pytest.raises(penumbra.ParameterError, match="unknown output 'albedo'"):
        renderer.render(scene, "pcss", outputs=["albedo"])
    with pytest.raises(penumbra.ParameterError, match="list of image names"):
        renderer.render(scene, "pcss", outputs="visibility")

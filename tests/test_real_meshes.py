"""Real meshes from ../shared/meshes with every method (issue 8): each
renders, or fails with the error class and reason decided here (the table in
docs/stability.md is this table). Skipped when the meshes are absent; never
copied into the repository. Sponza (66k triangles) and the full bunny are
`slow`."""

from __future__ import annotations

import numpy as np
import pytest

import penumbra
from stress_scenes import FAST, MESHES, METHODS, VOLUME_METHODS, check_images

# mesh file -> (expected error for the volume methods or None, slow)
# The reasons come from ../shared/meshes/SOURCES.md's topology table.
NOT_MANIFOLD = (penumbra.MeshError, ["not a 2-manifold"])
NOT_CLOSED = (penumbra.MeshError, ["not closed", "boundary edges"])
EXPECTED: dict[str, tuple[tuple[type[Exception], list[str]] | None, bool]] = {
    "cube.obj": (None, False),
    "spot.obj": (None, False),
    "teapot-mcguire-closed.obj": (None, False),
    # Open (5 holes in the bottom), edge-manifold.
    "bun_zipper.ply": (NOT_CLOSED, True),
    # 70 non-manifold edges, 40 duplicate faces, holes.
    "bun_zipper_res4.ply": (NOT_MANIFOLD, False),
    # Open boxes with a duplicated side face each (8 non-manifold edges).
    "CornellBox-Original.obj": (NOT_MANIFOLD, False),
    # 481 non-manifold edges, 4712 boundary edges.
    "sponza.obj": (NOT_MANIFOLD, True),
}


def cases() -> list:
    out = []
    for name, (_, slow) in EXPECTED.items():
        for method in METHODS:
            marks = [pytest.mark.slow] if slow else []
            out.append(pytest.param(name, method, marks=marks, id=f"{name}-{method}"))
    return out


@pytest.fixture(scope="module")
def loaded() -> dict[str, penumbra.Scene]:
    if not MESHES.is_dir():
        pytest.skip(f"the shared meshes are not at {MESHES.resolve()}")
    return {}


def scene_of(loaded: dict[str, penumbra.Scene], name: str) -> penumbra.Scene:
    if name not in loaded:
        loaded[name] = penumbra.scenes.from_mesh(str(MESHES / name), width=48, height=48)
    return loaded[name]


@pytest.mark.parametrize("name, method", cases())
def test_real_mesh_renders_or_names_the_reason(renderer: penumbra.Renderer, loaded: dict[str, penumbra.Scene], name: str, method: str) -> None:
    scene = scene_of(loaded, name)
    error = EXPECTED[name][0]
    if error is not None and method in VOLUME_METHODS:
        with pytest.raises(error[0]) as info:
            renderer.render(scene, method, **FAST[method])
        message = str(info.value)
        assert f"'{name}'" in message, f"the message names the mesh: {message}"
        for word in error[1]:
            assert word in message, f"{word!r} not in {message!r}"
        return
    result = renderer.render(scene, method, **FAST[method])
    check_images(result, f"{name}/{method}")
    assert (result.object_id == 1).any(), "the mesh is in view"


@pytest.mark.parametrize("name", ["bun_zipper.ply", "bun_zipper_res4.ply"])
def test_open_bunnies_with_open_edges_as_silhouettes(renderer: penumbra.Renderer, loaded: dict[str, penumbra.Scene], name: str) -> None:
    """The open bunny renders with boundary edges as silhouettes; the
    non-manifold low-res one is refused even then (non-manifold edges never
    are accepted)."""
    if name == "bun_zipper.ply":
        pytest.importorskip("trimesh")
    scene = scene_of(loaded, name)
    for method in sorted(VOLUME_METHODS):
        if name == "bun_zipper_res4.ply":
            with pytest.raises(penumbra.MeshError, match="not a 2-manifold"):
                renderer.render(scene, method, open_edges="silhouette", **FAST[method])
        else:
            check_images(renderer.render(scene, method, open_edges="silhouette", **FAST[method]))


def test_cornell_box_relative_indices_are_resolved(loaded: dict[str, penumbra.Scene]) -> None:
    """trimesh 5.2 misreads the Cornell box's relative (negative) face
    indices (SOURCES.md); from_mesh reads such OBJ files itself. The file's
    box spans 2.02 x 1.99 x 2.03 (SOURCES.md's bounding box); from_mesh scales
    its largest extent to 2.5. (trimesh's reading spans 1.15 in x.)"""
    mesh = scene_of(loaded, "CornellBox-Original.obj").meshes[1]
    extents = mesh.vertices.max(axis=0) - mesh.vertices.min(axis=0)
    assert len(mesh.faces) == 36
    np.testing.assert_allclose(extents, 2.5 * np.array([2.02, 1.99, 2.03]) / 2.03, atol=0.01)

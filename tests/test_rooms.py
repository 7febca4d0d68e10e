"""Rooms lit from inside (issue 31, docs/omnidirectional.md): every method
against the truth and under a rotation of the whole scene, over the room
suite of `penumbra.rooms` at 32x32, and the cube against the frustum along
face boundaries.

The truth here is `reference` at 256 samples with maps of 256 (the room
suite's own truth, 1024 samples, is benchmarks/rooms.py's): at 32x32 it
moves at most 0.3% of pixels by more than 0.1 under the rotation. Bounds
are the measured worst over the suite with a margin (the commands in the
comments); a failing test leaves the method's, the truth's and their
difference's images under test-artifacts/rooms/.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

import penumbra
from penumbra import rooms
from penumbra.comparison import PAPER
from stress_scenes import MESHES, check_images
from test_projection import MAPPED, seam_band, seam_renders
from test_real_meshes import leave_images

SIZE = 32
TRUTH = {"truth_samples": 256, "truth_map_size": 256}
ARTIFACTS = Path(__file__).resolve().parents[1] / "test-artifacts" / "rooms"
CORNELL = MESHES / "CornellBox-Original.obj"
# `reference` at low samples, the cheap way to the truth, beside the others.
# Maps of 256, as the truth's (at its default 2048 it takes 30 s a render here).
PARAMS: dict[str, dict[str, Any]] = {"reference": {"n_samples": 64, "map_size": 256}}


@pytest.fixture(scope="module")
def suite() -> dict[str, penumbra.Scene]:
    return rooms.room_suite(SIZE, str(CORNELL) if CORNELL.exists() else None)


@pytest.fixture(scope="module")
def images(renderer: penumbra.Renderer, suite: dict[str, penumbra.Scene]) -> dict:
    """Every scene's truth and its rotated copy's, rendered once for the module."""
    out: dict = {}
    rooms.measure(renderer, suite, [], images=out, **TRUTH)
    return out


def measured(renderer: penumbra.Renderer, suite: dict[str, penumbra.Scene], images: dict, method: str) -> list[rooms.RoomRow]:
    rows = rooms.measure(renderer, suite, [method], params=PARAMS, images=images, **TRUTH)
    assert len(rows) == len(suite) >= 6
    return rows


def check_rows(rows: list[rooms.RoomRow], images: dict, off_bound: float | None, moved_bound: float) -> None:
    """Every row within the bounds; on failure, the images of the rows that fail are left behind."""
    failing = [r for r in rows if r.off is None or (off_bound is not None and max(r.off, r.off_rotated) > off_bound) or r.moved > moved_bound]  # type: ignore[operator]
    for r in failing:
        for turned in (False, True):
            if (r.scene, r.method, turned) in images:
                leave_images(f"{r.method} {r.scene}{' rotated' if turned else ''}", images[(r.scene, r.method, turned)], images[(r.scene, "truth", turned)], ARTIFACTS)
    assert not failing, [f"{r.scene}: off {r.off}, rotated {r.off_rotated}, moved {r.moved} {r.refused}" for r in failing]


def test_the_suite_has_eight_lights_in_three_rooms(suite: dict[str, penumbra.Scene], renderer: penumbra.Renderer) -> None:
    if not CORNELL.exists():
        pytest.skip("../shared/meshes is absent: the Cornell box's three lights are missing")
    assert len(suite) >= 8 and len({name.split()[0] for name in suite}) == 3
    cubes = 0
    for name, scene in suite.items():
        result = renderer.render(scene, "hard", map_size=64)
        check_images(result, name)
        cubes += result.stats["cube_map"]
    # The walls cast nothing (casters.rs), so where the pillar and the shelf
    # and their penumbrae lie within one frustum no coarser than the cube,
    # the map is that frustum (issue 30); where they surround the light, or
    # the Cornell box's blocks stand wide below it, cube faces: 6 of 9.
    assert 0 < cubes < len(suite), cubes


def test_a_rotated_scene_renders_the_same_image(suite: dict[str, penumbra.Scene], renderer: penumbra.Renderer) -> None:
    """The rotation turns the camera with the scene: the same pixels see the
    same points (positions turned, within float error; a pixel on an edge
    between two surfaces may see the other one)."""
    scene = suite["room middle"]
    a = renderer.render(scene, "hard", map_size=256)
    b = renderer.render(rooms.rotated(scene), "hard", map_size=256)
    turn = rooms._rotation(*rooms.ROTATION)
    same = np.abs(a.position @ turn.T - b.position).max(axis=-1) < 1e-3
    assert same.mean() > 0.99, same.mean()
    assert (a.object_id == b.object_id).mean() > 0.99


def test_adaptive_samples_the_same_points_of_the_light_when_the_scene_turns(suite: dict[str, penumbra.Scene], renderer: penumbra.Renderer) -> None:
    """adaptive's quadtree starts from the light square's four corners; with
    the square's frame built from the world axes the turned room put them on
    other points of the light, split other cells and moved 2.3% of the
    pixels under the shelf (2.0% in the room's middle). With the camera's
    frame (light_sampling::camera_basis) it moved 0.4% and 1.5%: in the
    room's middle the light is at the centre of the scene's box, and the
    disk's axis (towards that centre) was straight down there and rounding
    noise in the turned copy; it is the camera's view direction now
    (light_sampling::scene_axis), and the two move 0.4% and 0.1% (measured,
    32x32; benchmarks/rooms.py prints the same). Needs no truth: the scene
    against its turned copy."""
    moved = {}
    for name in ("room under_shelf", "room middle"):
        scene = suite[name]
        a = renderer.render(scene, "adaptive").visibility
        b = renderer.render(rooms.rotated(scene), "adaptive").visibility
        moved[name] = float((np.abs(a - b) > rooms.THRESHOLD).mean())
    assert moved["room under_shelf"] <= 0.01 and moved["room middle"] <= 0.005, moved


# Measured at 32x32 with this truth (rooms.measure over the suite): pcss
# moves at most 0.1% of pixels (1.1% with the plane test) against
# reference's 0.6% (64 samples, maps of 256), pcf at most 1.4%;
# before the fix pcss moved up to 6.0% and pcf 3.5%. Off the truth pcss
# (blocker_test "behind" and blocker_depth "cone_farthest", the defaults)
# is at most 3.1% (room under_shelf), 2.1% elsewhere; with the mean
# blocker depth (Fernando's) 6.7% under the shelf, whose underside,
# from its edge in to over the light, pulls the mean nearer the light than
# the edge that casts the far walls' penumbra, and widens it; with the
# paper's plane test 6.5% at the ceiling corner and under the shelf, where
# its search and filter take the walls beside a receiver for blockers
# (`python benchmarks/rooms.py --size 32 --methods pcss [--param
# blocker_test=plane]`). The Cornell box lit near its left wall was 14.6%
# with the paper's centre test: there the light's sphere straddles the
# short block's front face, which the truth sees half lit and the centre's
# test dark; with pcss's defaults (the horizon repair, the behind test)
# it is 1.3%. pcf (a fixed kernel, no penumbra estimate) is not held to the
# truth.
PCSS_OFF: dict[str, float] = {}
PCSS_OFF_ELSEWHERE = 0.05


@pytest.mark.parametrize("method", ["pcss", "pcf"])
def test_cube_face_filters_do_not_depend_on_where_the_faces_cut(renderer: penumbra.Renderer, suite: dict[str, penumbra.Scene], images: dict, method: str) -> None:
    rows = measured(renderer, suite, images, method)
    check_rows(rows, images, None, 0.02)
    if method == "pcss":
        for row in rows:
            check_rows([row], images, PCSS_OFF.get(row.scene, PCSS_OFF_ELSEWHERE), 0.02)
        reference = measured(renderer, suite, images, "reference")
        # pcss moves no more pixels than reference at 64 samples does (its
        # noise), over the suite.
        assert sum(r.moved for r in rows) <= sum(r.moved for r in reference), (  # type: ignore[misc]
            [r.moved for r in rows],
            [r.moved for r in reference],
        )


def test_pcss_is_within_five_percent_of_the_truth_in_every_room(renderer: penumbra.Renderer, suite: dict[str, penumbra.Scene], images: dict) -> None:
    """Issue 31's target for the method `render` uses by default: 3.1% at
    worst (under the shelf), 6.7% there with the mean blocker depth
    (blocker_depth="mean", the paper's)."""
    check_rows(measured(renderer, suite, images, "pcss"), images, 0.05, 0.02)


# blocker_test="cone" (the option): only points inside the cone from the
# receiver to the light are blockers, and the search taps are spread by
# scale (as many per octave of the cone's reach), so a blocker close to the
# receiver is found however near the nearest geometry is. Measured at 32x32
# with this truth: at most PCSS_CONE_OFF of pixels off (`python
# benchmarks/rooms.py --size 32 --methods pcss --param blocker_test=cone`,
# with the suite's own truth: 3.5% worst, 1.0% mean, against 7.7% and 3.4%
# for the default); with uniform taps it was 17.1% (whole umbrae lit).
PCSS_CONE_OFF = 0.05


def test_pcss_with_the_cone_test_is_within_five_percent_of_the_truth_in_every_room(renderer: penumbra.Renderer, suite: dict[str, penumbra.Scene], images: dict) -> None:
    own = {k: v for k, v in images.items() if k[1] == "truth"}
    rows = rooms.measure(renderer, suite, ["pcss"], params={"pcss": {"blocker_test": "cone"}}, images=own, **TRUTH)
    assert len(rows) == len(suite) >= 6
    check_rows(rows, own, PCSS_CONE_OFF, 0.02)
    reference = measured(renderer, suite, images, "reference")
    assert sum(r.moved for r in rows) <= sum(r.moved for r in reference), ([r.moved for r in rows], [r.moved for r in reference])  # type: ignore[misc]
    print({r.scene: round(max(r.off, r.off_rotated), 4) for r in rows})  # type: ignore[type-var]


# The other methods over the suite, at 32x32 (`python -m pytest
# tests/test_rooms.py -m slow`): held to the issue's targets (off the truth
# within 5% of pixels, moved within 2%); those that miss them fail as
# measured (strict xfail: a fix that meets them turns the test red).
SLOW = [
    ("pvm", {}, None),
    # Off the truth by 0.3% at worst since its coverage term clips each
    # silhouette edge at the light's plane (`python benchmarks/rooms.py
    # --size 32 --methods wedges`); 5.4% before in the Cornell box lit over
    # its tall block, where the back wall, beyond the light from the
    # block's near vertical edge, lost about half the light to that edge.
    ("wedges", {}, None),
    ("reference", {}, None),
    # Moved 0.4% at worst, off the truth 3.9% (`python benchmarks/rooms.py
    # --size 32 --methods adaptive`); 2.3% moved before its light square's
    # corners were placed in the camera's frame (light_sampling::camera_basis)
    # rather than one built from the world axes, 1.5% before the disk's axis
    # took the camera's view where the light sits at the scene box's centre
    # (light_sampling::scene_axis).
    ("adaptive", {}, None),
    # Off the truth by 1.4% at worst, moved 1.2% (room under_shelf); with
    # 5.1's contours (coarse_contour="centres") moved 5.0%: a coarse level's
    # contour half a texel off along the shelf's edge, which runs along the
    # texel grid unless the room is turned.
    ("backprojection", {}, None),
    # pvmf's defaults since issue 31 (the disk kernel, no blur, radius
    # offsets, umbra="skip", s_e=0.02; the "recommended setting" before):
    # 3.9% at worst with this truth (room under_shelf), moved 0.4%; 4.2% with
    # the suite's own (docs/omnidirectional.md).
    ("pvmf", {}, None),
    (
        "pvmf",
        PAPER["pvmf"],
        "PVMF's paper settings (unit offsets, 5.1) flag 70-79% of the pixels in rooms and its screen-space blur (n_blur 12 pixels) "
        "smears the walls: off the truth by 23-28% of pixels in most rooms (see docs/omnidirectional.md)",
    ),
    # The paper's settings with scaled offsets and no blur: off the truth by
    # 5.6% at worst at 32x32 (the Cornell box's ceiling light; 4.8% at
    # 64x64, benchmarks/rooms.py), held to 6.5%; moved 0.2%.
    ("pvmf", {**PAPER["pvmf"], "offsets": "radius", "n_blur": 0}, None),
]
# The issue's target, off the truth within 5% of pixels, but where a bound measured here says otherwise.
OFF_BOUND = {("pvmf", "kernel=square-n_blur=0-offsets=radius-umbra=filter-s_e=0.5"): 0.065}


def setting_id(params: dict[str, Any]) -> str:
    return "-".join(f"{k}={v}" for k, v in params.items())


@pytest.mark.slow
@pytest.mark.parametrize(("method", "params", "failing"), SLOW, ids=[f"{m}{'-' + setting_id(p) if p else ''}" for m, p, _ in SLOW])
def test_every_method_in_rooms(
    renderer: penumbra.Renderer, suite: dict[str, penumbra.Scene], images: dict, method: str, params: dict[str, Any], failing: str | None, request: pytest.FixtureRequest
) -> None:
    if failing:
        request.applymarker(pytest.mark.xfail(strict=True, reason=failing))
    rows = rooms.measure(renderer, suite, [method], params={method: {**PARAMS.get(method, {}), **params}}, images=images, **TRUTH)
    check_rows(rows, images, OFF_BOUND.get((method, setting_id(params)), 0.05), 0.02)


@pytest.mark.parametrize("method", MAPPED)
def test_seams_match_the_frustum_within_its_resolution_error(renderer: penumbra.Renderer, method: str) -> None:
    """Where both projections apply (a floor whose shadow crosses the seam
    between two cube faces), the largest difference between the cube and the
    frustum within two texels of a face boundary is within the frustum's own
    resolution error there (its largest difference from a map four times
    finer), or, for methods that jitter their taps, their sampling noise
    (seed 0 against 1), whichever is larger (issue 31). Measured (band of 71
    pixels; difference, resolution error, noise): hard 0, 0, 0; pcf 0.153,
    0.153, 0.022 (at that pixel the cube equals the finer map); pcss 0.047,
    0.089, 0.056; reference 0.054, 0.108, 0.110; adaptive 0.043, 0.083, 0;
    pvm 0.010, 0.010, 0; pvmf 0.090, 0.120, 0.007; wedges 0, 0, 0;
    backprojection 0.045, 0.055, 0. The 1e-6 is for the ties."""
    scene, params, frustum, cube = seam_renders(renderer, method, 256)
    finer = renderer.render(scene, method, projection="frustum", **{**params, "map_size": 1024})
    band = seam_band(cube, np.asarray(scene.light.center, dtype=np.float32), 256, texels=2)
    assert band.sum() > 20, "the seams cross the image"
    allowance = np.abs(frustum.visibility - finer.visibility)[band].max()
    if "seed" in penumbra.method_info(method).defaults():
        other = renderer.render(scene, method, projection="frustum", **{**params, "seed": 1})
        other_cube = renderer.render(scene, method, projection="cube", **{**params, "seed": 1})
        allowance = max(allowance, np.abs(frustum.visibility - other.visibility)[band].max(), np.abs(cube.visibility - other_cube.visibility)[band].max())
    difference = np.abs(cube.visibility - frustum.visibility)[band].max()
    if difference > allowance + 1e-6:
        leave_images(f"seam {method}", cube.visibility, frustum.visibility, ARTIFACTS)
    assert difference <= allowance + 1e-6, (method, difference, allowance)

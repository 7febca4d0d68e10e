"""Property-based tests of every method on random scenes (issue 8).

Scenes: a closed caster (sphere, box or needle-thin box), sometimes a second
one touching or intersecting it, over a ground slab; scales from 1e-7 to 1e10
(issue 22), and the ends of that range for every method on fixed scenes;
light radius from 0 to larger than the casters; the light's surface from
1e-3 to 5 caster sizes off the caster; light elevations down to grazing.
Invariants: no NaN or Inf in any image, visibility in [0, 1], identical
output for identical input, visibility unchanged (within a measured
tolerance) when the whole scene is uniformly scaled and translated, and
convergence to `hard` as the radius goes to 0.

CI runs a derandomized handful of examples (`derandomize=True`: the same
examples on every run); `pytest -m slow` runs many more.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
import pytest
import trimesh
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import penumbra
from stress_scenes import FAST, METHODS, SIZE, check_images


@dataclass(frozen=True)
class SceneSpec:
    """Everything that defines a random scene, in units of the caster size."""

    kind: str
    size: float
    height: float
    yaw: float
    second: str
    radius: float
    gap: float
    elevation: float
    azimuth: float

    def build(self, scale: float = 1.0, offset: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> penumbra.Scene:
        t = np.asarray(offset, dtype=np.float64)
        place = lambda p: np.asarray(p, dtype=np.float64) * scale + t  # noqa: E731
        meshes = [_mesh(_slab(), "ground", 0, place)]
        caster = _caster(self.kind, self.size, self.height, self.yaw)
        meshes.append(_mesh(caster, "caster", 1, place))
        top = float(caster.bounds[1][1])
        if self.second != "none":
            # Touching: resting on the caster's top; intersecting: sunk into it.
            sink = 0.0 if self.second == "touching" else 0.3 * self.size
            other = trimesh.creation.box(extents=(0.5 * self.size,) * 3)
            other.apply_translation((0.2 * self.size, top + 0.25 * self.size - sink, 0.1 * self.size))
            meshes.append(_mesh(other, "second", 2, place))
            top = float(other.bounds[1][1])
        # The light looks down at the caster from `elevation` degrees; its
        # surface is `gap` caster sizes beyond the casters' bounding sphere.
        centre = np.array([0.0, self.height, 0.0])
        reach = float(np.linalg.norm(np.vstack([m.vertices for m in meshes[1:]]) - place(centre), axis=1).max()) / scale
        e, a = math.radians(self.elevation), math.radians(self.azimuth)
        direction = np.array([math.cos(e) * math.cos(a), math.sin(e), math.cos(e) * math.sin(a)])
        distance = reach + self.radius + self.gap * self.size
        if self.elevation < 60.0:
            # Low (grazing) lights must stand back for one shadow-map frustum
            # (80 degrees half-angle) to cover the 4 x 4 slab; else SceneError.
            distance += 12.0
        light_centre = centre + direction * distance
        light = penumbra.SphereLight(place(light_centre), self.radius * scale, intensity=40.0 * scale**2)
        cam = penumbra.Camera(eye=place((0.0, 6.0, 7.0)), target=place((0.0, 0.5, 0.0)), fov_y=45.0, width=SIZE, height=SIZE)
        return penumbra.Scene(meshes, light, cam, name="random")


def _slab() -> trimesh.Trimesh:
    m = trimesh.creation.box(extents=(4.0, 0.2, 4.0))
    m.apply_translation((0.0, -0.1, 0.0))
    return m


def _caster(kind: str, size: float, height: float, yaw: float) -> trimesh.Trimesh:
    if kind == "sphere":
        m = trimesh.creation.icosphere(subdivisions=2, radius=0.5 * size)
    elif kind == "box":
        m = trimesh.creation.box(extents=(size, size, size))
    else:  # needle: 1e-3 thin
        m = trimesh.creation.box(extents=(size, 1e-3 * size, 1e-3 * size))
    m.apply_transform(trimesh.transformations.rotation_matrix(math.radians(yaw), (0, 1, 0)))
    m.apply_translation((0.0, height, 0.0))
    return m


def _mesh(m: trimesh.Trimesh, name: str, object_id: int, place: Any) -> penumbra.Mesh:
    return penumbra.Mesh(place(m.vertices), m.faces, albedo=0.7, object_id=object_id, name=name)


def spec_from(floats: Callable[[float, float], float], sampled_from: Callable[[list[Any]], Any], booleans: Callable[[], bool], integers: Callable[[int, int], int]) -> SceneSpec:
    """One random scene from the ranges of the property tests, drawn with the
    four given functions: hypothesis's strategies (:func:`scene_specs`) or a
    seeded generator (benchmarks/stability.py draws many more this way)."""
    size = floats(0.3, 1.5)
    kind = sampled_from(["sphere", "box", "needle"])
    # Heights from sunk into the ground (intersecting) through touching to floating.
    height = sampled_from([0.3 * size, 0.5 * size]) if booleans() else floats(0.6 * size, 2.5)
    radius = sampled_from([0.0, 1e-4 * size]) if integers(0, 3) == 0 else floats(0.02, 2.5) * size
    return SceneSpec(
        kind=kind,
        size=size,
        height=height,
        yaw=floats(0.0, 90.0),
        second=sampled_from(["none", "none", "touching", "intersecting"]),
        radius=radius,
        gap=sampled_from([1e-3, 1e-2]) if booleans() else floats(0.05, 5.0),
        # Down to 10 degrees above the ground: grazing on the slab.
        elevation=floats(10.0, 90.0),
        azimuth=floats(0.0, 360.0),
    )


@st.composite
def scene_specs(draw: st.DrawFn) -> SceneSpec:
    return spec_from(lambda a, b: draw(st.floats(a, b)), lambda xs: draw(st.sampled_from(xs)), lambda: draw(st.booleans()), lambda a, b: draw(st.integers(a, b)))


def render(renderer: penumbra.Renderer, scene: penumbra.Scene, method: str, **extra: object) -> penumbra.RenderResult:
    """Renders: every valid random scene renders (a light near the caster
    that sees the slab beyond one frustum's 80 degrees takes cube faces)."""
    return renderer.render(scene, method, **{**FAST[method], **extra})


CI = settings(max_examples=3, derandomize=True, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture, HealthCheck.filter_too_much])
LONG = settings(CI, max_examples=40)
# Each property runs on CI's examples, and on LONG's under `pytest -m slow`.
EXAMPLES = [pytest.param(CI, id="ci"), pytest.param(LONG, id="long", marks=pytest.mark.slow)]


def on_random_scenes(examples: settings, check: Callable[..., None], **strategies: st.SearchStrategy[Any]) -> None:
    """`check(spec, ...)` on random scenes (and the other `strategies`), as many as `examples` says."""
    examples(given(spec=scene_specs(), **strategies)(check))()

# Log10 of the uniform scale of the whole scene, from 1e-7 to 1e10 (issue
# 22: a scene 1e-7 across was refused as "the light intersects mesh" by an
# absolute tolerance). The core enforces what lies beyond: coordinates past
# +-1e18 and scenes less than 1e-18 across are refused with a typed error
# naming float32 (tests/test_bad_input.py); `benchmarks/stability.py --limits`
# measured where visibility goes wrong without those bounds (docs/stability.md).
MIN_EXPONENT, MAX_EXPONENT = -7, 10
# pvm's visibility changed at 1e10 (0.054 of the pixels by more than 0.1 on
# FIXED_SPEC at 32 px) until its cutting plane was built from unit vectors
# (issue 22 item 1, docs/real_meshes.md); every method now spans the range.


def scales(method: str) -> st.SearchStrategy[int]:
    return st.integers(MIN_EXPONENT, MAX_EXPONENT)


def _finite_in_range_and_deterministic(renderer: penumbra.Renderer, spec: SceneSpec, exponent: int, method: str) -> None:
    scene = spec.build(scale=10.0**exponent)
    a = render(renderer, scene, method)
    check_images(a, f"{spec} at 1e{exponent}")
    b = render(renderer, scene, method)
    for key in a.images:
        np.testing.assert_array_equal(a.images[key], b.images[key], err_msg=key)


@pytest.mark.parametrize("examples", EXAMPLES)
@pytest.mark.parametrize("method", METHODS)
def test_random_scenes_are_finite_in_range_and_deterministic(renderer: penumbra.Renderer, method: str, examples: settings) -> None:
    on_random_scenes(examples, lambda spec, exponent: _finite_in_range_and_deterministic(renderer, spec, exponent, method), exponent=scales(method))


# Visibility of the same scene at another scale and place. Measured by
# `XDG_RUNTIME_DIR=/tmp python3 benchmarks/stability.py --scenes 20` (seed 8:
# 20 random scenes from the ranges of `scene_specs`/`SCALES`, 19 rendered,
# one refused; 32x32, FAST parameters): hard, pcf, pcss, pvm and reference
# gave identical visibility in every case (fraction of pixels differing by
# more than 0.1: max 0.0000; mean absolute difference: max 0.0000). The
# bounds allow two pixels of 1024 and a mean of 1e-3 on top of that measured
# 0, for float32 rounding moving a texel boundary in scenes not yet seen.
# pvmf with the paper's offsets was not: max 0.1182 of pixels differing by
# more than 0.1 (p99 0.1178, median 0.0088), mean difference max 0.0312. The
# cause is the paper's extrusion offsets (5.1): unit vectors, one world unit
# whatever the scene's size, so the mask is relatively smaller in a larger
# scene (the worst scene: 225 masked pixels at scale 1, 96 at scale 10).
# With `offsets="radius"` (scaled by the light's radius) the same scene is
# identical to 2e-8. So the invariance is tested with radius offsets, and
# the paper's scale dependence is tested as such below.
MISMATCH_FRACTION = 2 / 1024
MEAN_DIFFERENCE = 1e-3
# Parameters that make each method independent of the scene's units.
SCALE_FREE: dict[str, dict[str, object]] = {"pvmf": {"offsets": "radius"}}


def visibility_difference(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    d = np.abs(a.astype(np.float64) - b.astype(np.float64))
    return float((d > 0.1).mean()), float(d.mean())


def _scale_and_translation_invariant(renderer: penumbra.Renderer, spec: SceneSpec, exponent: int, method: str) -> None:
    extra = SCALE_FREE.get(method, {})
    base = render(renderer, spec.build(), method, **extra)
    s = 10.0**exponent
    moved = render(renderer, spec.build(scale=s, offset=(3.0 * s, -2.0 * s, 5.0 * s)), method, **extra)
    check_images(moved)
    frac, mean = visibility_difference(base.visibility, moved.visibility)
    assert frac <= MISMATCH_FRACTION and mean <= MEAN_DIFFERENCE, f"{spec} scaled by 1e{exponent}: {frac:.4f} of pixels differ, mean {mean:.4f}"


@pytest.mark.parametrize("examples", EXAMPLES)
@pytest.mark.parametrize("method", METHODS)
def test_uniform_scale_and_translation_leave_visibility_unchanged(renderer: penumbra.Renderer, method: str, examples: settings) -> None:
    on_random_scenes(examples, lambda spec, exponent: _scale_and_translation_invariant(renderer, spec, exponent, method), exponent=scales(method))


# The ends of the range for every method, on fixed scenes (the derandomized
# CI examples above need not reach them): a box with a touching second box,
# and a needle under a light wider than itself.
FIXED_SPECS = [
    SceneSpec("box", 1.0, 1.5, 20.0, "touching", 0.3, 1.0, 70.0, 30.0),
    SceneSpec("needle", 0.8, 1.2, 45.0, "none", 1.2, 0.5, 80.0, 200.0),
]


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("exponent", [MIN_EXPONENT, MAX_EXPONENT])
@pytest.mark.parametrize("spec", FIXED_SPECS, ids=["box", "needle"])
def test_the_ends_of_the_scale_range_leave_visibility_unchanged(renderer: penumbra.Renderer, method: str, exponent: int, spec: SceneSpec) -> None:
    _finite_in_range_and_deterministic(renderer, spec, exponent, method)
    _scale_and_translation_invariant(renderer, spec, exponent, method)


def translated_default_scene(offset: float, scale: float = 1.0) -> penumbra.Scene:
    """sphere_on_plane moved by ``offset`` along every axis (and scaled by
    ``scale`` about the origin first), as issue 22 reported it."""
    base = penumbra.scenes.get("sphere_on_plane", width=SIZE, height=SIZE)
    move = np.diag([scale, scale, scale, 1.0])
    move[:3, 3] = offset
    meshes = [penumbra.Mesh(m.vertices, m.faces, transform=move @ m.transform.astype(np.float64), object_id=i, name=m.name) for i, m in enumerate(base.meshes)]
    light = penumbra.SphereLight(base.light.center.astype(np.float64) * scale + offset, base.light.radius * scale, intensity=base.light.intensity)
    assert base.camera is not None
    c = base.camera
    camera = penumbra.Camera(np.asarray(c.eye) * scale + offset, np.asarray(c.target) * scale + offset, c.up, c.fov_y, SIZE, SIZE)
    return penumbra.Scene(meshes, light, camera)


@pytest.mark.parametrize("method", METHODS)
def test_a_scene_1e7_from_the_origin_or_1e7_smaller_renders(renderer: penumbra.Renderer, method: str) -> None:
    """Issue 22 item 4: both were refused ("the light intersects mesh
    'ground'") by an absolute tolerance. Scaled by 1e-7 the visibility is the
    scale-1 visibility; 1e7 from the origin float32 resolves one unit, so the
    scene renders as rounded there (the sphere's shadow still falls on the ground)."""
    base = renderer.render(translated_default_scene(0.0), method, **FAST[method])
    tiny = renderer.render(translated_default_scene(0.0, scale=1e-7), method, **FAST[method])
    check_images(tiny, "scaled by 1e-7")
    frac, mean = visibility_difference(base.visibility, tiny.visibility)
    assert frac <= MISMATCH_FRACTION and mean <= MEAN_DIFFERENCE, (frac, mean)
    far = renderer.render(translated_default_scene(1e7), method, **FAST[method])
    check_images(far, "translated by 1e7")
    ground = far.object_id == 0
    assert (far.visibility[ground] < 0.5).any() and (far.visibility[ground] == 1.0).any()


WORST_PVMF_SCENE = SceneSpec("sphere", 1.2829627341064935, 2.1686630364650665, 61.79789065224047, "touching", 2.2453816619167126, 0.01, 79.80142386110028, 133.13616364973657)


def test_pvmf_worst_measured_scene_is_invariant_with_radius_offsets(renderer: penumbra.Renderer) -> None:
    """The largest pvmf difference benchmarks/stability.py found (seed 8, 0.1182 of the pixels with unit offsets)."""
    _scale_and_translation_invariant(renderer, WORST_PVMF_SCENE, 1, "pvmf")


def test_pvmf_unit_offsets_are_world_units_as_the_paper_specifies(renderer: penumbra.Renderer) -> None:
    """The paper's extrusion offsets (5.1) are unit vectors: in a scene ten
    times larger the mask covers fewer pixels (measured: 225 against 96)."""
    small = render(renderer, WORST_PVMF_SCENE.build(), "pvmf", offsets="unit")
    large = render(renderer, WORST_PVMF_SCENE.build(scale=10.0, offset=(30.0, -20.0, 50.0)), "pvmf", offsets="unit")
    assert large.stats["masked_pixels"] < 0.6 * small.stats["masked_pixels"]


# As the radius goes to 0, every method but pcf (whose kernel is fixed in
# texels, independent of the light) tends to `hard`: the fraction of pixels
# differing from `hard` by more than 0.5 at radius 1e-5 caster sizes
# (single texels on outlines, where the methods' own biases and sampling
# differ from hard's). Measured by the same command as above (19 scenes per
# method): max 0.0010 pcss, 0.0000 pvm, 0.0098 pvmf (p99 0.0094, median
# 0.0020), 0.0020 reference; over all four max 0.0098, p99 0.0083. Bound:
# 1.5 x the largest measured value (0.0098 is 10 pixels of 1024; 0.015 is 15).
CONVERGED_MISMATCH = 0.015
SOFT_METHODS = [m for m in METHODS if m not in ("hard", "pcf")]


def _converges_to_hard(renderer: penumbra.Renderer, spec: SceneSpec, method: str) -> None:
    from dataclasses import replace

    hard = render(renderer, replace(spec, radius=0.0).build(), "hard").visibility
    tiny = render(renderer, replace(spec, radius=1e-5 * spec.size).build(), method).visibility
    mismatch = float((np.abs(tiny - hard) > 0.5).mean())
    assert mismatch <= CONVERGED_MISMATCH, f"{spec}: {mismatch:.4f} of pixels differ from hard"
    wide = render(renderer, replace(spec, radius=0.5 * spec.size).build(), method).visibility
    # Smaller lights are closer to hard than larger ones (or equally close).
    assert np.abs(tiny - hard).mean() <= np.abs(wide - hard).mean() + 1e-3


@pytest.mark.parametrize("examples", EXAMPLES)
@pytest.mark.parametrize("method", SOFT_METHODS)
def test_small_radius_converges_to_hard(renderer: penumbra.Renderer, method: str, examples: settings) -> None:
    on_random_scenes(examples, lambda spec: _converges_to_hard(renderer, spec, method))


def test_pcf_with_a_zero_kernel_is_hard(renderer: penumbra.Renderer) -> None:
    spec = SceneSpec("box", 1.0, 1.5, 20.0, "none", 0.3, 1.0, 70.0, 30.0)
    scene = spec.build()
    hard = render(renderer, scene, "hard").visibility
    pcf = renderer.render(scene, "pcf", map_size=256, kernel=0.0).visibility
    assert float((np.abs(pcf - hard) > 0.5).mean()) <= CONVERGED_MISMATCH

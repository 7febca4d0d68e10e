"""The renderer's pass cache (issue 9): reuse of passes a change does not
affect, bit-identical results with and without it, invalidation, and keys
that are not too loose."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import penumbra
from stress_scenes import new_renderer

pytestmark = pytest.mark.gpu

SIZE = 40
MAP = 128
# Alternatives for string parameters, by name (the first that differs is used).

@pytest.fixture(scope="module")
def cached() -> penumbra.Renderer:
    return new_renderer(pass_cache=True)


@pytest.fixture(scope="module")
def uncached() -> penumbra.Renderer:
    return new_renderer(pass_cache=False)


def scene(name: str = "overlapping_casters", **kw: Any) -> penumbra.Scene:
    return penumbra.scenes.get(name, width=SIZE, height=SIZE, **kw)


def assert_same(a: penumbra.RenderResult, b: penumbra.RenderResult, what: str) -> None:
    assert sorted(a.images) == sorted(b.images), what
    for key in a.images:
        # Bit for bit: equal arrays of equal dtype (NaN would fail, and must not occur).
        assert a.images[key].dtype == b.images[key].dtype, (what, key)
        np.testing.assert_array_equal(a.images[key], b.images[key], err_msg=f"{what}: {key}")
    skip = ("reused_", "shadow_maps_rendered", "silhouette_cache_hits", "pass_cache")
    stats = lambda r: {k: v for k, v in r.stats.items() if not k.startswith(skip)}  # noqa: E731
    assert stats(a) == stats(b), what
    assert a.params == b.params, what


def test_switch_and_defaults(cached: penumbra.Renderer, uncached: penumbra.Renderer) -> None:
    assert cached.pass_cache and not uncached.pass_cache
    assert penumbra.Renderer.__init__.__defaults__ == ("auto", True)
    s = scene()
    for _ in range(2):
        # n_blur 12 (the paper's; the default 0 runs no blur pass): every pass.
        r = uncached.render(s, "pvmf", map_size=MAP, n_blur=12)
        assert r.stats["pass_cache"] == 0 and r.stats["reused_passes"] == 0 and r.reused_passes == []
        assert list(r.timings) == ["gbuffer", "shadow_map", "mask", "solid_layers", "object_map", "estimation", "blur", "shading", "readback"]
    assert set(uncached.pass_cache_entries().values()) == {0}


def test_late_parameter_reuses_earlier_passes(cached: penumbra.Renderer) -> None:
    cached.clear_pass_cache()
    s = scene()
    first = cached.render(s, "pvmf", map_size=MAP, n_blur=4)
    assert first.stats["reused_passes"] == 0 and first.stats["pass_cache"] == 1
    second = cached.render(s, "pvmf", map_size=MAP, n_blur=8)
    assert second.reused_passes == ["estimation", "gbuffer", "mask", "shadow_map", "solid_layers"]
    assert second.stats["reused_passes"] == 5
    # Reused passes report no timing: they did not run.
    assert list(second.timings) == ["blur", "shading", "readback"]
    assert second.stats["shadow_maps_rendered"] == 0 and second.stats["silhouette_cache_hits"] == 0
    # The estimate's counters survive reuse; the blur's are this render's.
    for key in ("masked_pixels", "filtered_pixels", "mask_quads", "silhouette_edges"):
        assert second.stats[key] == first.stats[key], key
    assert second.stats["blurred_pixels"] > 0
    # pvm falloff: only the visibility pass and shading run.
    cached.render(s, "pvm", map_size=MAP, falloff=True)
    pvm = cached.render(s, "pvm", map_size=MAP, falloff=False)
    assert pvm.reused_passes == ["gbuffer", "object_map", "penumbra_volumes", "shadow_map", "solid_layers"]
    assert list(pvm.timings) == ["visibility", "shading", "readback"]
    # A light radius change keeps the G-buffer only: the light's maps cover
    # the casters and the penumbrae the radius sizes (issue 30).
    wider = cached.render(scene(light_radius=0.8), "pvm", map_size=MAP, falloff=False)
    assert wider.reused_passes == ["gbuffer"]
    entries = cached.pass_cache_entries()
    assert entries["penumbra_volumes"] == 1 and entries["gbuffer"] >= 1
    cached.clear_pass_cache()
    assert set(cached.pass_cache_entries().values()) == {0}


def test_sweep_is_bit_identical_with_and_without_the_cache(cached: penumbra.Renderer, uncached: penumbra.Renderer) -> None:
    cached.clear_pass_cache()
    configs: list[tuple[penumbra.Scene, str, dict[str, Any]]] = []
    for radius in (0.3, 0.6):
        s = scene(light_radius=radius)
        configs += [(s, "pvmf", {"map_size": MAP, "n_blur": n}) for n in (0, 4, 12)]
        configs += [(s, "pvmf", {"map_size": MAP, "s_p": 1.0})]
        configs += [(s, "pvm", {"map_size": MAP, "falloff": f}) for f in (True, False)]
        configs += [(s, "pvm", {"map_size": MAP, "edges": e}) for e in ("two", "one", "chain")]
        configs += [(s, m, {"map_size": MAP}) for m in ("hard", "pcf", "pcss")]
        configs += [(s, "reference", {"n_samples": 4})]
    configs += [(scene(light_radius=0.0), "pvmf", {"map_size": MAP, "n_blur": n}) for n in (0, 4)]
    reused = 0
    for s, method, params in configs:
        a = cached.render(s, method, intermediates=True, **params)
        b = uncached.render(s, method, intermediates=True, **params)
        assert_same(a, b, f"{method} {params} r={s.light.radius}")
        reused += a.stats["reused_passes"]
    assert reused > len(configs), "the sweep reused passes"


def test_changes_invalidate(cached: penumbra.Renderer, uncached: penumbra.Renderer) -> None:
    base = scene()
    shift = np.eye(4, dtype=np.float32)
    shift[1, 3] = 0.05
    lifted = [
        penumbra.Mesh(m.vertices, m.faces, albedo=m.albedo, object_id=m.object_id, name=m.name, normals=m.normals, transform=shift @ m.transform)
        for m in base.meshes[1:]
    ]
    moved_mesh = penumbra.Scene(meshes=[base.meshes[0], *lifted], light=base.light, camera=base.camera, ambient=base.ambient)
    light = base.light
    assert base.camera is not None
    variants: list[tuple[str, penumbra.Scene, dict[str, Any], list[str]]] = [
        ("geometry", moved_mesh, {}, []),
        ("camera", base.with_camera(penumbra.Camera.look_at(np.add(base.camera.eye, 0.1), base.camera.target, width=SIZE, height=SIZE)), {}, ["mask", "object_map", "shadow_map", "solid_layers"]),
        ("light centre", base.with_light(penumbra.SphereLight(np.add(light.center, 0.05), light.radius, intensity=light.intensity)), {}, ["gbuffer"]),
        # The light's maps cover the casters' penumbrae, which the radius sizes.
        ("light radius", base.with_light(light.with_radius(light.radius * 0.5)), {}, ["gbuffer"]),
        # Maps of 128 and 64 texels have object maps of the same 64 (object_map::side).
        ("map size", base, {"map_size": MAP // 2}, ["gbuffer", "object_map"]),
        # The object map is the first surface's, whatever the bias keeps.
        ("bias", base, {"bias": "midpoint"}, ["gbuffer", "mask", "object_map", "solid_layers"]),
        ("s_e", base, {"s_e": 0.25}, ["gbuffer", "object_map", "shadow_map", "solid_layers"]),
        ("s_p", base, {"s_p": 1.0}, ["gbuffer", "mask", "object_map", "shadow_map", "solid_layers"]),
        ("seed", base, {"seed": 3}, ["gbuffer", "mask", "object_map", "shadow_map", "solid_layers"]),
    ]
    for what, s, params, expect in variants:
        p = {"map_size": MAP, **params}
        cached.render(base, "pvmf", map_size=MAP)
        a = cached.render(s, "pvmf", **p)
        assert a.reused_passes == expect, what
        assert_same(a, uncached.render(s, "pvmf", **p), what)



def test_kept_geometry_is_the_same_as_fresh_and_any_change_prepares_afresh(uncached: penumbra.Renderer) -> None:
    """The renderer keeps the last geometry it rendered (geometry_cache.rs),
    with or without the pass cache: a render of the same meshes starts from
    it, bit-identical to one that prepares afresh (after clear_pool); a mesh
    changed in place, or another light, is prepared (or its casters found)
    afresh, and renders as a fresh renderer does."""
    r = uncached
    base = scene()
    methods = [("hard", {}), ("pvmf", {}), ("pcss", {"projection": "cube"})]
    r.clear_pool()
    fresh = {m: r.render(base, m, map_size=MAP, **p) for m, p in methods}
    assert [f.stats["reused_geometry"] for f in fresh.values()] == [0, 1, 1]
    for m, p in methods:
        kept = r.render(base, m, map_size=MAP, **p)
        assert kept.stats["reused_geometry"] == 1 and kept.reused_passes == [], m
        assert_same(kept, fresh[m], m)
    # Another light of the same geometry: kept geometry, its own casters.
    smaller = base.with_light(base.light.with_radius(base.light.radius * 0.5))
    kept = r.render(smaller, "pvmf", map_size=MAP)
    r.clear_pool()
    prepared = r.render(smaller, "pvmf", map_size=MAP)
    assert (kept.stats["reused_geometry"], prepared.stats["reused_geometry"]) == (1, 0)
    assert_same(kept, prepared, "light radius")
    # A vertex moved in place in the scene's own array: prepared afresh, and the image follows.
    moved = scene()
    before = r.render(moved, "hard", map_size=MAP)
    moved.meshes[-1].vertices[:, 1] += 0.05
    after = r.render(moved, "hard", map_size=MAP)
    assert after.stats["reused_geometry"] == 0
    assert not np.array_equal(after.visibility, before.visibility)
    r.clear_pool()
    assert_same(after, r.render(moved, "hard", map_size=MAP), "moved in place")

def _alternative(method: str, name: str, value: Any) -> Any:
    if isinstance(value, bool):
        return not value
    if isinstance(value, str):
        choices = penumbra.method_info(method).param(name).choices or ()
        return next(c for c in choices if c != value)
    if isinstance(value, int):
        return value // 2 if value > 1 else value + 1
    return value * 2.0 if value > 0 else 0.5


# reference, raytraced and triangle_masks cache nothing of their own (the G-buffer's key is tested with the others).
@pytest.mark.parametrize("method", [m for m in penumbra.methods() if m not in ("reference", "raytraced", "triangle_masks")])
def test_every_parameter_is_in_the_keys_it_must_be(method: str, cached: penumbra.Renderer, uncached: penumbra.Renderer) -> None:
    """Changes each parameter alone after a render with the defaults: were a
    pass keyed too loosely (a parameter it reads left out), the cached render
    would reuse a stale output and differ from the one from scratch."""
    s = scene(light_radius=0.6)
    # 64 texels: on a map fitted to the casters and their penumbrae (issue
    # 30), 128 texels are fine enough that `hard`'s offsets of one or two
    # texels move no pixel at 40 x 40.
    base = {"map_size": MAP // 2}
    defaults = uncached.render(s, method, **base).params
    differing = 0
    for name, value in sorted(defaults.items()):
        params = {**base, name: _alternative(method, name, value)}
        try:
            expected = uncached.render(s, method, **params)
        except penumbra.ParameterError:
            continue
        cached.render(s, method, **base)
        got = cached.render(s, method, **params)
        assert_same(got, expected, f"{method} {name}={params[name]}")
        differing += not np.array_equal(expected.visibility, cached.render(s, method, **base).visibility)
    # Most parameters change the picture, so the comparisons above have teeth
    # (at least four: on this scene `wedges` reads the map's hard boundary
    # off its wedges' quad planes, so its bias settings change no pixel, and
    # the scene has no acute corner for `acute_wedges`).
    assert differing >= min(len(defaults) // 2, 4), (method, differing, len(defaults))

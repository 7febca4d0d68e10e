"""The method registry as Python sees it: declarations, the checks they
drive, and the resource pool every method's passes draw from."""

from __future__ import annotations

import numpy as np
import pytest

import penumbra
from stress_scenes import NOT_YET


def test_every_implemented_method_declares_its_parameters() -> None:
    infos = penumbra.method_info()
    assert sorted(infos) == sorted(penumbra.methods())
    for name, info in infos.items():
        assert info.paper and info.params, name
        names = [p.name for p in info.params]
        assert len(set(names)) == len(names), name
        for p in info.params:
            assert p.type in ("bool", "int", "float", "choice") and p.doc, (name, p)
            if p.type == "choice":
                assert p.choices and p.default in p.choices, (name, p)
            if p.type in ("int", "float"):
                assert p.minimum is not None and p.maximum is not None and p.minimum <= p.default <= p.maximum, (name, p)


def test_declarations_are_what_the_renderer_checks(renderer: penumbra.Renderer) -> None:
    """A render's effective parameters are exactly the declared defaults,
    and a value just outside a declared range is refused, naming the range."""
    scene = penumbra.scenes.get(width=8, height=8)
    for name, info in penumbra.method_info().items():
        cheap = {"n_samples": 4} if name in ("reference", "raytraced", "triangle_masks") else {}
        if "map_size" in info.defaults():
            cheap["map_size"] = 64
        result = renderer.render(scene, name, **cheap)
        assert result.params == {**info.defaults(), **cheap}, name
        for p in info.params:
            if p.type == "int":
                with pytest.raises(penumbra.ParameterError, match=rf"'{p.name}'.*\[{int(p.minimum)}, {int(p.maximum)}\]"):
                    renderer.render(scene, name, **{p.name: int(p.maximum) + 1})
            if p.type == "choice":
                with pytest.raises(penumbra.ParameterError, match=p.name):
                    renderer.render(scene, name, **{p.name: "no-such-choice"})
    with pytest.raises(penumbra.ParameterError, match=f"unknown or unimplemented method '{NOT_YET or 'magic'}'"):
        penumbra.method_info(NOT_YET or "magic")
    # pvmf defaults to slope where 5.5 uses second_depth (docs/real_meshes.md).
    assert penumbra.method_info("pvmf").param("bias").default == "slope"
    with pytest.raises(penumbra.ParameterError, match="no parameter"):
        penumbra.method_info("hard").param("kernel")


def test_renders_reuse_pooled_resources_and_the_pool_is_released() -> None:
    """A second identical render allocates nothing new (the kept geometry,
    dropped in between, comes back from the pool); `clear_pool` frees what
    no render or cache holds; results are the same with a warm pool."""
    r = penumbra.Renderer(timing="cpu", pass_cache=False)
    scene = penumbra.scenes.get(width=32, height=32)
    first = r.render(scene, "pvmf", map_size=128, n_blur=2)
    after_first = r.pool_stats()
    assert after_first["bytes_in_use"] > 0, "the geometry kept for the next render (geometry_cache.rs)"
    r.clear_pass_cache()
    assert r.pool_stats()["bytes_in_use"] == 0, "without a pass cache a finished render holds nothing but the geometry it keeps, which clear_pass_cache drops"
    second = r.render(scene, "pvmf", map_size=128, n_blur=2)
    assert r.pool_stats() == after_first, "the second render reused every texture, buffer and bind group"
    assert np.array_equal(first.visibility, second.visibility) and np.array_equal(first.radiance, second.radiance)
    r.clear_pool()
    cleared = r.pool_stats()
    assert cleared["textures"] == cleared["buffers"] == cleared["bind_groups"] == cleared["bytes_free"] == 0
    third = r.render(scene, "pvmf", map_size=128, n_blur=2)
    assert np.array_equal(first.visibility, third.visibility)


def test_cached_outputs_stay_in_use_until_the_cache_drops_them() -> None:
    r = penumbra.Renderer(timing="cpu")
    scene = penumbra.scenes.get(width=32, height=32)
    r.render(scene, "pvm", map_size=128)
    held = r.pool_stats()["bytes_in_use"]
    assert held > 0, "the pass cache holds the G-buffer, shadow map and volume map"
    r.clear_pass_cache()
    stats = r.pool_stats()
    assert stats["bytes_in_use"] == 0 and stats["bytes_free"] == 0

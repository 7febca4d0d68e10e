"""Mitsuba 3 ground truth of a Penumbra scene (SPEC section 6).

:func:`ground_truth` exports the scene (same world-space meshes, one-sided
diffuse BSDFs with the same albedo and winding, the sphere emitter with the
same radiance, a perspective sensor with the same look-at and vertical fov,
``hdrfilm`` with a box filter, linear float output) and renders

- **radiance** with Mitsuba's ``direct`` integrator (``hide_emitters``), and
- **visibility**: the solid-angle fraction of the light visible from the
  surface point seen through each pixel's centre (as Penumbra samples it),
  estimated with stratified directions over the light's cone and one shadow
  ray each; directions below the point's horizon count as hidden (the surface
  itself hides them). ``visibility_cosine`` weights each direction by its
  cosine with the normal, which is the visibility that makes
  ``albedo/pi * E * v`` exact.

Results are cached on disk, keyed by a hash of the exported scene, camera,
kind, spp, seed and variant. Rendering with a second seed gives the ground
truth's own noise (:class:`GroundTruth` ``.second``).

The variant is ``llvm_ad_rgb`` when Dr.Jit loads an LLVM it can use (LLVM 15
and 16 crash it; Debian's ``libllvm19`` works and is preferred), else
``scalar_rgb``; the visibility estimator needs the llvm variant.
"""

from __future__ import annotations

import glob
import hashlib
import json
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable

import numpy as np

from penumbra.errors import GroundTruthError
from penumbra.scene import Camera, Scene, world_geometry

__all__ = ["GroundTruth", "ground_truth", "variant", "export", "default_cache_dir"]

# Bump when the export or the estimators change, so stale cache entries are ignored.
_FORMAT = 2
_mi: Any = None
_dr: Any = None


def _usable_llvm() -> str | None:
    """A libLLVM Dr.Jit can use (major >= 17), preferring the newest."""
    candidates = []
    for path in glob.glob("/usr/lib/*/libLLVM-*.so*") + glob.glob("/usr/lib/*/libLLVM.so.*") + glob.glob("/usr/lib/llvm-*/lib/libLLVM*.so*"):
        digits = "".join(c if c.isdigit() else " " for c in Path(path).name).split()
        if digits and int(digits[0]) >= 17:
            candidates.append((int(digits[0]), path))
    return max(candidates)[1] if candidates else None


def _load() -> tuple[Any, Any]:
    """Imports Mitsuba once, choosing the variant (see the module docstring).
    ``PENUMBRA_MITSUBA_VARIANT`` forces one."""
    global _mi, _dr
    if _mi is not None:
        return _mi, _dr
    if "DRJIT_LIBLLVM_PATH" not in os.environ:
        llvm = _usable_llvm()
        if llvm:
            os.environ["DRJIT_LIBLLVM_PATH"] = llvm
    try:
        import drjit as dr
        import mitsuba as mi
    except ImportError as e:
        raise GroundTruthError(f"Mitsuba 3 is not installed ({e}); `pip install mitsuba==3.9.1`") from None
    forced = os.environ.get("PENUMBRA_MITSUBA_VARIANT")
    chosen = forced or "scalar_rgb"
    if not forced and "llvm_ad_rgb" in mi.variants():
        try:
            major = dr.detail.llvm_version()[0] if dr.has_backend(dr.JitBackend.LLVM) else 0
        except Exception:  # no LLVM found at all
            major = 0
        # LLVM 15 and 16 abort the process ("Cannot select ... fminimum").
        if major >= 17:
            chosen = "llvm_ad_rgb"
    try:
        mi.set_variant(chosen)
    except Exception as e:
        raise GroundTruthError(f"Mitsuba variant {chosen!r} is unavailable: {e}") from None
    _mi, _dr = mi, dr
    return mi, dr


def variant() -> str:
    """The Mitsuba variant ground truth renders with."""
    mi, _ = _load()
    return str(mi.variant())


def default_cache_dir() -> Path:
    """``$PENUMBRA_CACHE_DIR`` or ``~/.cache/penumbra``, plus ``groundtruth``."""
    root = os.environ.get("PENUMBRA_CACHE_DIR") or os.path.join(os.path.expanduser("~"), ".cache", "penumbra")
    return Path(root) / "groundtruth"


def _exported(mesh: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """A mesh's world-space vertices (float32), faces (uint32, counter-clockwise
    from the front: reversed where the transform mirrors, as the core does)
    and unit vertex normals (float32) or None, as Mitsuba gets them."""
    world = world_geometry(mesh)
    normals = None if world.normals is None else world.normals.astype(np.float32)
    return world.vertices.astype(np.float32), world.faces.astype(np.uint32), normals


def _camera_of(scene: Scene, camera: Camera | None) -> Camera:
    camera = camera or scene.camera
    if camera is None:
        from penumbra.errors import CameraError

        raise CameraError("the scene has no camera; pass camera=penumbra.Camera(...)")
    return camera


def _scene_key(scene: Scene, camera: Camera) -> hashlib._Hash:
    h = hashlib.sha256()
    h.update(json.dumps({"format": _FORMAT, "camera": [list(camera.eye), list(camera.target), list(camera.up), camera.fov_y, camera.width, camera.height],
                         "light": [scene.light.center.tolist(), scene.light.radius, scene.light.intensity.tolist()]}).encode())
    for mesh in scene.meshes:
        vertices, faces, normals = _exported(mesh)
        for array in (vertices, faces, mesh.albedo, normals):
            h.update(b"-" if array is None else np.ascontiguousarray(array).tobytes())
    return h


def _mesh(mi: Any, mesh: Any, index: int, with_bsdf: bool) -> Any:
    props = mi.Properties()
    if with_bsdf:
        props["bsdf"] = mi.load_dict({"type": "diffuse", "reflectance": {"type": "rgb", "value": mesh.albedo.astype(float).tolist()}})
    vertices, faces, normals = _exported(mesh)
    m = mi.Mesh(f"mesh_{index}_{mesh.name}", len(vertices), len(faces), props=props, has_vertex_normals=normals is not None)
    params = mi.traverse(m)
    params["vertex_positions"] = type(params["vertex_positions"])(vertices.ravel())
    params["faces"] = type(params["faces"])(faces.ravel())
    if normals is not None:
        params["vertex_normals"] = type(params["vertex_normals"])(normals.ravel())
    params.update()
    return m


def _sensor(mi: Any, scene: Scene, camera: Camera, spp: int, seed: int) -> dict[str, Any]:
    vertices = np.concatenate([_exported(m)[0] for m in scene.meshes])
    distances = np.linalg.norm(vertices - np.asarray(camera.eye), axis=1)
    return {
        "type": "perspective",
        "fov": float(camera.fov_y),
        "fov_axis": "y",
        # Clip planes from the scene's extent, so tiny or huge scenes are not clipped.
        "near_clip": float(max(distances.min() * 1e-3, 1e-7)),
        "far_clip": float(distances.max() * 2 + 1e-6),
        "to_world": mi.ScalarTransform4f().look_at(origin=list(camera.eye), target=list(camera.target), up=list(camera.up)),
        "film": {"type": "hdrfilm", "width": camera.width, "height": camera.height, "rfilter": {"type": "box"}, "pixel_format": "rgb", "component_format": "float32"},
        "sampler": {"type": "ldsampler", "sample_count": spp, "seed": seed},
    }


# Mitsuba's float32 sphere sampling loses the light's cone when it is tiny
# (measured, radiance of a lit plane at 5 units: +1.4% at r = 0.01, +13% at
# r = 0.003, zero at r = 0.001). Below this r/d, the light is exported as a
# point light of the same intensity, exact for the irradiance up to (r/d)^2.
POINT_LIGHT_RATIO = 0.005


def _light_as_point(scene: Scene) -> bool:
    """Whether the light is exported as a point light (radius 0, or r/d below
    :data:`POINT_LIGHT_RATIO` for the nearest vertex)."""
    radius = float(scene.light.radius)
    if radius == 0:
        return True
    nearest = min(float(np.linalg.norm(_exported(m)[0] - scene.light.center, axis=1).min()) for m in scene.meshes)
    return radius < POINT_LIGHT_RATIO * nearest


def export(scene: Scene, camera: Camera | None = None, *, spp: int = 256, seed: int = 0, light: bool = True) -> Any:
    """The Mitsuba scene of a Penumbra scene, ready for ``mi.render``.
    ``light=False`` leaves the light sphere out (for visibility queries)."""
    mi, _ = _load()
    camera = _camera_of(scene, camera)
    desc: dict[str, Any] = {
        "type": "scene",
        # Emitter sampling alone is unbiased for a sphere light and far less noisy
        # than mixing in BSDF samples, which rarely hit a small light.
        "integrator": {"type": "direct", "emitter_samples": 1, "bsdf_samples": 0, "hide_emitters": True},
        "sensor": _sensor(mi, scene, camera, spp, seed),
    }
    for i, mesh in enumerate(scene.meshes):
        desc[f"mesh_{i}"] = _mesh(mi, mesh, i, with_bsdf=True)
    if light:
        l = scene.light
        if not _light_as_point(scene):
            radiance = l.radiance
            assert radiance is not None
            desc["light"] = {"type": "sphere", "center": l.center.astype(float).tolist(), "radius": float(l.radius),
                             "emitter": {"type": "area", "radiance": {"type": "rgb", "value": radiance.astype(float).tolist()}}}
        else:
            desc["light"] = {"type": "point", "position": l.center.astype(float).tolist(), "intensity": {"type": "rgb", "value": l.intensity.astype(float).tolist()}}
    try:
        return mi.load_dict(desc)
    except Exception as e:
        raise GroundTruthError(f"Mitsuba refused the exported scene: {e}") from None


def _stratified(n: int) -> tuple[int, int]:
    """A near-square grid of at least n cells."""
    a = int(math.ceil(math.sqrt(n)))
    return a, int(math.ceil(n / a))


def _render_visibility(scene: Scene, camera: Camera, spp: int, seed: int) -> dict[str, np.ndarray]:
    mi, dr = _load()
    if not str(mi.variant()).startswith("llvm"):
        raise GroundTruthError(
            "visibility ground truth needs Mitsuba's llvm_ad_rgb variant (install Debian's libllvm19); "
            f"the variant in use is {mi.variant()}"
        )
    mscene = export(scene, camera, spp=4, seed=seed, light=False)
    sensor = mscene.sensors()[0]
    w, h = camera.width, camera.height
    pixels = w * h
    center = mi.Point3f(*[float(c) for c in scene.light.center])
    radius = float(scene.light.radius)
    gx, gy = _stratified(spp)
    count = gx * gy
    visible = np.zeros(pixels)
    visible_cos = np.zeros(pixels)
    cos_total = np.zeros(pixels)
    # Rays through pixel centres (SPEC 3: pixel (i, j) is sampled at its centre).
    idx = dr.arange(mi.UInt32, pixels)
    pos = mi.Point2f((mi.Float(idx % w) + 0.5) / w, (mi.Float(idx // w) + 0.5) / h)
    ray, _ = sensor.sample_ray(0.0, 0.0, pos, mi.Point2f(0.5, 0.5))
    si = mscene.ray_intersect(ray)
    valid = np.array(si.is_valid(), dtype=bool)
    # Shading frame as Penumbra's: the geometric normal, vertex normals where given.
    n = si.sh_frame.n
    to_light = center - si.p
    dist = dr.norm(to_light)
    axis = to_light / dr.maximum(dist, 1e-30)
    # Cone of the light seen from p: sin(alpha) = r / d (d > r: no surface
    # touches the light). 1 - cos(alpha) = s / (1 + sqrt(1 - s)) with s = (r/d)^2
    # keeps tiny lights' cones in float32 (1 - sqrt(1 - s) would cancel to 0).
    s2 = dr.square(radius / dr.maximum(dist, 1e-30))
    one_minus_cos_alpha = s2 / (1 + dr.safe_sqrt(1 - s2))
    batch = max(1, min(count, (1 << 22) // max(pixels, 1)))
    rng = mi.PCG32(size=pixels * batch, initstate=seed * 0x9E3779B9 + 12345)
    for start in range(0, count, batch):
        k = min(batch, count - start)
        if k != batch:
            rng = mi.PCG32(size=pixels * k, initstate=seed * 0x9E3779B9 + 12345 + start)
        lane = dr.arange(mi.UInt32, pixels * k)
        pixel = lane % pixels
        cell = lane // pixels + start
        p = dr.gather(mi.Point3f, dr.ravel(si.p), pixel)
        nn = dr.gather(mi.Vector3f, dr.ravel(n), pixel)
        ax = dr.gather(mi.Vector3f, dr.ravel(axis), pixel)
        omc = dr.gather(mi.Float, one_minus_cos_alpha, pixel)
        d_ = dr.gather(mi.Float, dist, pixel)
        fr = mi.Frame3f(ax)
        # Stratified jittered sample of the cone, uniform in solid angle.
        u1 = (mi.Float(cell % gx) + rng.next_float32()) / gx
        u2 = (mi.Float(cell // gx) + rng.next_float32()) / gy
        one_minus_cos_t = u1 * omc
        cos_t = 1 - one_minus_cos_t
        sin_t = dr.safe_sqrt(one_minus_cos_t * (2 - one_minus_cos_t))
        phi = 2 * dr.pi * u2
        local = mi.Vector3f(sin_t * dr.cos(phi), sin_t * dr.sin(phi), cos_t)
        direction = fr.to_world(local)
        # Distance to the light sphere's near side along the direction (ray-sphere).
        b = dr.dot(direction, ax) * d_
        t_light = b - dr.safe_sqrt(b * b - d_ * d_ + radius * radius) if radius > 0 else d_
        cosine = dr.dot(direction, nn)
        above = cosine > 0
        shadow = mi.Ray3f(p + nn * (1e-5 * dr.maximum(d_, 1.0)), direction)
        shadow.maxt = dr.maximum(t_light * (1 - 1e-4), 0)
        occluded = mscene.ray_test(shadow, active=above)
        seen = above & ~occluded
        v = np.array(dr.select(seen, 1.0, 0.0), dtype=np.float64).reshape(k, pixels)
        c = np.array(dr.maximum(cosine, 0.0), dtype=np.float64).reshape(k, pixels)
        visible += v.sum(0)
        visible_cos += (v * c).sum(0)
        cos_total += c.sum(0)
    with np.errstate(invalid="ignore", divide="ignore"):
        cosine_weighted = np.where(cos_total > 0, visible_cos / np.where(cos_total > 0, cos_total, 1), 0.0)
    # Distance from the eye (Mitsuba starts camera rays at the near clip plane, so si.t is shorter).
    eye = mi.Point3f(*[float(c) for c in camera.eye])
    depth = np.array(dr.norm(si.p - eye), dtype=np.float64)
    return {
        "visibility": np.where(valid, visible / count, 0.0).reshape(h, w).astype(np.float32),
        "visibility_cosine": np.where(valid, cosine_weighted, 0.0).reshape(h, w).astype(np.float32),
        "hit_distance": np.where(valid, depth, 0.0).reshape(h, w).astype(np.float32),
    }


def radiance_spp(spp: int) -> int:
    """The sample count Mitsuba's ``ldsampler`` uses for ``spp``: the next power of 4."""
    return 4 ** max(0, math.ceil(math.log(spp, 4) - 1e-9))


def _render_radiance(scene: Scene, camera: Camera, spp: int, seed: int) -> dict[str, np.ndarray]:
    mi, _ = _load()
    spp = radiance_spp(spp)
    mscene = export(scene, camera, spp=spp, seed=seed)
    image = mi.render(mscene, spp=spp, seed=seed)
    return {"radiance": np.array(image, dtype=np.float32).reshape(camera.height, camera.width, -1)[..., :3]}


_RENDERERS = {"radiance": _render_radiance, "visibility": _render_visibility}


@dataclass
class GroundTruth:
    """Mitsuba's images of a scene (linear float32), how they were made, and
    optionally the same rendered with another seed (``second``) for the noise floor."""

    images: dict[str, np.ndarray]
    spp: int
    seed: int
    variant: str
    seconds: dict[str, float]
    cached: dict[str, bool]
    second: GroundTruth | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def radiance(self) -> np.ndarray:
        return self.images["radiance"]

    @property
    def visibility(self) -> np.ndarray:
        return self.images["visibility"]

    @property
    def visibility_cosine(self) -> np.ndarray:
        return self.images["visibility_cosine"]


def _check(spp: int, seed: int, kinds: Iterable[str]) -> list[str]:
    from penumbra.errors import ParameterError

    if isinstance(spp, bool) or not isinstance(spp, (int, np.integer)) or spp < 1 or spp > 1 << 20:
        raise ParameterError(f"spp must be an integer in [1, 2^20], got {spp!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ParameterError(f"seed must be a non-negative integer, got {seed!r}")
    kinds = list(kinds)
    unknown = [k for k in kinds if k not in _RENDERERS]
    if unknown or not kinds:
        raise ParameterError(f"kinds must be among {list(_RENDERERS)}, got {kinds}")
    return kinds


def ground_truth(
    scene: Scene,
    camera: Camera | None = None,
    *,
    spp: int = 256,
    seed: int = 0,
    noise_seed: int | None = None,
    kinds: Iterable[str] = ("radiance", "visibility"),
    cache_dir: str | os.PathLike[str] | None = None,
    cache: bool = True,
) -> GroundTruth:
    """Mitsuba ground truth of ``scene`` seen by ``camera`` (default: the scene's).

    ``spp`` light samples per pixel (radiance: Mitsuba's sampler, which rounds
    to a power of 4; visibility: a stratified grid of at least ``spp`` cells).
    ``noise_seed`` renders everything again with that seed into ``.second``.
    Results are read from and written to ``cache_dir`` (default
    :func:`default_cache_dir`) unless ``cache=False``."""
    kinds = _check(spp, seed, kinds)
    camera = _camera_of(scene, camera)
    folder = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    chosen = variant()
    base = _scene_key(scene, camera)
    images: dict[str, np.ndarray] = {}
    seconds: dict[str, float] = {}
    cached: dict[str, bool] = {}
    for kind in kinds:
        key = base.copy()
        key.update(json.dumps([kind, int(spp), int(seed), chosen]).encode())
        path = folder / f"{kind}-{key.hexdigest()[:32]}.npz"
        if cache and path.exists():
            with np.load(path) as stored:
                images.update({k: stored[k] for k in stored.files if k != "seconds"})
                seconds[kind] = float(stored["seconds"])
            cached[kind] = True
            continue
        start = time.perf_counter()
        produced = _RENDERERS[kind](scene, camera, int(spp), int(seed))
        seconds[kind] = time.perf_counter() - start
        cached[kind] = False
        images.update(produced)
        if cache:
            folder.mkdir(parents=True, exist_ok=True)
            partial = path.with_suffix(".tmp.npz")
            arrays: dict[str, Any] = {"seconds": np.float64(seconds[kind]), **produced}
            np.savez_compressed(partial, **arrays)
            os.replace(partial, path)
    second = None
    if noise_seed is not None:
        if noise_seed == seed:
            from penumbra.errors import ParameterError

            raise ParameterError("noise_seed must differ from seed")
        second = ground_truth(scene, camera, spp=spp, seed=noise_seed, kinds=kinds, cache_dir=folder, cache=cache)
    extra = {"light_exported_as": "point" if _light_as_point(scene) else "sphere"}
    return GroundTruth(images=images, spp=int(spp), seed=int(seed), variant=chosen, seconds=seconds, cached=cached, second=second, extra=extra)

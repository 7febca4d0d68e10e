"""Where the light hidden from a method's stray umbra pixels is hidden
(issue 28; passes/solid_layers.rs): for each pixel in the umbra in truth
(visibility <= 0.02) that a method lights above 1/2, rays to 64 points of
the light's disk (as the map rays take them) are traced with Mitsuba; for
each ray's first blocking point, how many surfaces the light centre's ray
through that point crosses before it (0: the shadow map's own surface).
Then an ideal march (16 points along each ray, every surface exact) that
calls a point hidden where it lies inside a solid by parity over the first
2, 4 or 8 casters' surfaces along the centre's ray, or over the last 4 or
8 (-4, -8: paired from the far end, on rays with an even count of
surfaces): the share of the hidden rays it finds, and the pixels it would
leave above 1/2. On generated:2 (two hollow teapots, up to 14 surfaces on
a centre ray) `pvmf`'s 89 lit umbra pixels keep 79-85 above 1/2 whichever
layers: the blocking points lie behind 7 or more surfaces, in walls thin
enough that 16 points step over them.

    python benchmarks/occluder_layers.py 1 37 38 --method wedges --map-solids false

Needs the shared meshes and Mitsuba (the truth is cached as the tests cache it).
"""

from __future__ import annotations

import argparse

import numpy as np

import penumbra
from penumbra import mitsuba as pm_mitsuba
from penumbra import scenes

SPP = 256
POINTS = 64
MARCH = 16


def hits(scene, origins: np.ndarray, dirs: np.ndarray, count: int, eps: float) -> np.ndarray:
    """The distances of the first `count` surfaces along each ray (inf: none)."""
    mi, _ = pm_mitsuba._load()
    o = origins.copy()
    out = np.full((len(o), count), np.inf)
    travelled = np.zeros(len(o))
    for i in range(count):
        si = scene.ray_intersect(mi.Ray3f(mi.Point3f(*o.T.astype(np.float32)), mi.Vector3f(*dirs.T.astype(np.float32))))
        t = np.array(si.t, float)
        ok = np.isfinite(t) & np.array(si.is_valid())
        out[ok, i] = travelled[ok] + t[ok]
        step = np.where(ok, t + eps, 0.0)
        travelled += step
        o = o + dirs * step[:, None]
    return out


def study(seed: int, method: str, params: dict, size: int) -> None:
    scene = scenes.generate(seed, width=size)
    gt = pm_mitsuba.ground_truth(scene, spp=SPP, kinds=["visibility"]).visibility
    res = penumbra.Renderer().render(scene, method, outputs=["visibility", "object_id", "position", "normal"], **params)
    stray = (gt <= 0.02) & (res.object_id >= 0) & (res.visibility > 0.5)
    if not stray.any():
        print(f"generated:{seed} {method}: no umbra pixel lit above 1/2")
        return
    mscene = pm_mitsuba.export(scene, light=False)
    light, radius = np.asarray(scene.light.center, float), float(scene.light.radius)
    eps = 1e-4 * np.linalg.norm(light - np.asarray(scene.camera.target))
    p = res.position[stray].astype(float) + 1e-4 * res.normal[stray].astype(float)
    # The light's disk as each pixel sees it, an equal-area spiral (map_rays.wgsl's points).
    w = light - p
    w /= np.linalg.norm(w, axis=1)[:, None]
    e1 = np.cross(w, np.where(np.abs(w[:, :1]) > 0.7, [[0.0, 1.0, 0.0]], [[1.0, 0.0, 0.0]]))
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    e2 = np.cross(w, e1)
    i = np.arange(POINTS)
    rad, ang = np.sqrt((i + 0.5) / POINTS), i * 2.3999632
    goals = light + radius * rad[None, :, None] * (np.cos(ang)[None, :, None] * e1[:, None] + np.sin(ang)[None, :, None] * e2[:, None])
    seg = goals - p[:, None]
    length = np.linalg.norm(seg, axis=2).reshape(-1)
    dirs = (seg.reshape(-1, 3)) / length[:, None]
    first = hits(mscene, np.repeat(p, POINTS, axis=0), dirs, 1, eps)[:, 0]
    hidden = first < length
    # The blocking points, and the surfaces before them along the centre's rays.
    x = np.repeat(p, POINTS, axis=0)[hidden] + dirs[hidden] * first[hidden][:, None]
    to_x = x - light
    dist = np.linalg.norm(to_x, axis=1)
    before = (hits(mscene, np.repeat(light[None], len(x), 0), to_x / dist[:, None], 8, eps) < dist[:, None] - 3 * eps).sum(axis=1)
    print(f"generated:{seed} {method} {params}: {stray.sum()} umbra pixels lit, {hidden.mean():.3f} of their rays hidden")
    print(f"  surfaces before the blocking point along the centre's ray (0, 1, ...): {np.bincount(before, minlength=8).tolist()}")
    # The ideal march: points along each ray, inside a solid by parity over the first n surfaces.
    q = p[:, None, None] + ((np.arange(MARCH) + 0.5) / MARCH)[None, None, :, None] * seg[:, :, None]
    q = q.reshape(-1, 3)
    to_q = q - light
    qd = np.linalg.norm(to_q, axis=1)
    casters = penumbra.Scene(scene.meshes[1:], scene.light, scene.camera, name=scene.name)
    cscene = pm_mitsuba.export(casters, light=False)
    layers = hits(cscene, np.repeat(light[None], len(q), 0), to_q / qd[:, None], 24, eps)
    count = np.isfinite(layers).sum(axis=1)
    print(f"  casters' surfaces on the march points' centre rays: at most {int(count.max())}, an odd count on {float((count % 2).mean()):.3f} of them")
    for n in (2, 4, 8, -4, -8):
        inside = np.zeros(len(q), bool)
        if n > 0:
            for k in range(0, n, 2):
                inside |= (layers[:, k] <= qd) & (qd <= layers[:, k + 1])
        else:
            for k in range(0, -n, 2):
                # The stretch between the (k + 2)-th and (k + 1)-th surfaces from the far end.
                near = np.take_along_axis(layers, np.clip(count - 2 - k, 0, 23)[:, None], 1)[:, 0]
                far = np.take_along_axis(layers, np.clip(count - 1 - k, 0, 23)[:, None], 1)[:, 0]
                paired = (count % 2 == 0) & (count - 2 - k >= 0)
                inside |= paired & (near <= qd) & (qd <= far)
        found = inside.reshape(len(p), POINTS, MARCH).any(axis=2)
        seen = 1.0 - found.mean(axis=1)
        print(f"  {n} surfaces: finds {(found.reshape(-1) & hidden).sum() / hidden.sum():.3f} of the hidden rays "
              f"(hides {(found.reshape(-1) & ~hidden).sum()} seen ones); pixels left above 1/2: {(seen > 0.5).sum()} of {len(p)}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("seeds", type=int, nargs="+")
    ap.add_argument("--method", default="wedges")
    ap.add_argument("--map-solids", choices=["true", "false"], default=None, help="the method's map_solids (default: its default)")
    ap.add_argument("--size", type=int, default=96)
    args = ap.parse_args()
    params = {} if args.map_solids is None else {"map_solids": args.map_solids == "true"}
    for seed in args.seeds:
        study(seed, args.method, params, args.size)


if __name__ == "__main__":
    main()

"""A/B of two Vulkan drivers on the same build: every method's radiance and
visibility (defaults; `reference` at 16 samples; `raytraced` left out, it
needs ray queries) on the built-in scenes and two real meshes at 64x64,
saved by one run per driver and compared. Point a run at another driver with
the loader's VK_ICD_FILENAMES, e.g. the lavapipe of an older Mesa unpacked
with `dpkg -x` (docs/methods/raytraced.md):

    VK_ICD_FILENAMES=/path/to/old/lvp_icd.json python benchmarks/driver_ab.py render old.npz
    python benchmarks/driver_ab.py render new.npz
    python benchmarks/driver_ab.py compare old.npz new.npz
"""
import sys, numpy as np, penumbra
from pathlib import Path
MESHES = Path(__file__).resolve().parents[1] / ".." / "shared" / "meshes"
if sys.argv[1] == "render":
    scenes = {n: penumbra.scenes.get(n, width=64, height=64) for n in penumbra.scenes.names()}
    for name in ("spot.obj", "teapot-mcguire-closed.obj"):
        scenes[name] = penumbra.scenes.from_mesh(str(MESHES / name), width=64, height=64)
    r = penumbra.Renderer(timing="cpu", pass_cache=False)
    out = {}
    for s, scene in scenes.items():
        for m in penumbra.methods():
            if m == "raytraced":
                continue
            p = {"n_samples": 16} if m == "reference" else {}
            res = r.render(scene, m, **p)
            out[f"{s}|{m}|radiance"] = res.radiance
            out[f"{s}|{m}|visibility"] = res.visibility
    np.savez(sys.argv[2], **out)
else:
    a, b = np.load(sys.argv[2]), np.load(sys.argv[3])
    worst = {}
    for k in a.files:
        d = np.abs(a[k].astype(np.float64) - b[k])
        scale = max(float(np.abs(a[k]).max()), 1e-30)
        kind = k.split("|")[2]
        worst[kind] = max(worst.get(kind, (0, 0)), (float(d.max()) / scale, int((d > 0).sum())))
        if d.max() > 0:
            print(k, "max abs diff", d.max(), "relative to max", d.max() / scale, "pixels", int((d > 0).sum()))
    print("worst (relative max diff, pixels):", worst)

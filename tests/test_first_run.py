"""The first five minutes (issue 23): the first command's picture, timings a
user can trust, the smooth default sphere, and no driver noise on stderr."""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh

import penumbra
from penumbra import metrics
from penumbra.comparison import compare_methods, timed_render, timing_renderer


def python(code: str, env: dict[str, str], cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, env=env, cwd=cwd)


def without_runtime_dir(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k != "XDG_RUNTIME_DIR"}
    env.update(extra)
    return env


# What a fresh process reports: the runtime directory it ended up with, its
# mode and owner, and whether an adapter exists (the driver only complains
# when it starts).
PROBE = (
    "import os, stat, penumbra\n"
    "d = os.environ.get('XDG_RUNTIME_DIR')\n"
    "try:\n    penumbra.adapter_info(); gpu = True\n"
    "except penumbra.GpuUnavailableError:\n    gpu = False\n"
    "st = os.stat(d) if d and os.path.isdir(d) else None\n"
    "print(d); print(oct(stat.S_IMODE(st.st_mode)) if st else None); print(st.st_uid == os.getuid() if st else None); print(gpu)\n"
)


@pytest.mark.skipif(not hasattr(os, "getuid"), reason="XDG runtime directories are a POSIX matter")
def test_import_sets_a_private_runtime_dir_when_unset(tmp_path: Path) -> None:
    done = python(PROBE, without_runtime_dir(TMPDIR=str(tmp_path)), tmp_path)
    assert done.returncode == 0, done.stderr
    path, mode, ours, gpu = done.stdout.split()
    assert path == str(tmp_path / f"penumbra-runtime-{os.getuid()}")
    assert mode == "0o700" and ours == "True"
    assert "XDG_RUNTIME_DIR" not in done.stderr and done.stderr == "", done.stderr
    # A second process reuses it.
    again = python(PROBE, without_runtime_dir(TMPDIR=str(tmp_path)), tmp_path)
    assert again.stdout.split()[0] == path and again.stderr == ""


@pytest.mark.skipif(not hasattr(os, "getuid"), reason="XDG runtime directories are a POSIX matter")
def test_a_shared_or_loose_directory_is_not_reused(tmp_path: Path) -> None:
    loose = tmp_path / f"penumbra-runtime-{os.getuid()}"
    loose.mkdir(mode=0o755)
    loose.chmod(0o755)
    done = python(PROBE, without_runtime_dir(TMPDIR=str(tmp_path)), tmp_path)
    assert done.returncode == 0, done.stderr
    path, mode, ours, _ = done.stdout.split()
    assert path != str(loose) and Path(path).parent == tmp_path and mode == "0o700" and ours == "True"
    assert oct(loose.stat().st_mode & 0o777) == "0o755", "the loose directory is left as it was"


@pytest.mark.parametrize("value", ["mine", "does/not/exist"])
def test_a_runtime_dir_that_is_set_is_left_alone(tmp_path: Path, value: str) -> None:
    wanted = tmp_path / value
    if value == "mine":
        wanted.mkdir(mode=0o700)
    done = python(PROBE, {**os.environ, "XDG_RUNTIME_DIR": str(wanted), "TMPDIR": str(tmp_path)}, tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split()[0] == str(wanted)
    assert not (tmp_path / f"penumbra-runtime-{os.getuid()}").exists(), "no private directory made"


def test_the_command_line_prints_nothing_on_stderr(tmp_path: Path) -> None:
    # The CLI's entry point is `import penumbra` too; `info` starts the driver.
    done = subprocess.run([sys.executable, "-m", "penumbra", "info"], capture_output=True, text=True, timeout=300,
                          env=without_runtime_dir(TMPDIR=str(tmp_path)), cwd=tmp_path)
    assert done.returncode in (0, 2)
    if done.returncode == 0:
        assert done.stderr == "", done.stderr


# --- timings ---------------------------------------------------------------


def test_warm_time_is_the_median_of_the_timed_renders(renderer: penumbra.Renderer) -> None:
    scene = penumbra.scenes.get(width=48, height=48)
    result, timing = timed_render(renderer, scene, "pcss", repeats=5)
    assert len(timing.timed_ms) == 5
    assert timing.warm_ms == statistics.median(timing.timed_ms)
    assert timing.warm_ms <= statistics.median(timing.timed_ms)
    assert timing.cold_ms > 0 and result.method == "pcss"
    # Every timed render ran every pass: the renderer's pass cache was cleared.
    assert result.stats["reused_passes"] == 0
    # A budget stops after the first timed render once it is spent, never before.
    _, short = timed_render(renderer, scene, "hard", repeats=5, budget_s=0.0)
    assert len(short.timed_ms) == 1 and short.warm_ms == short.timed_ms[0]
    with pytest.raises(penumbra.ParameterError, match="repeats"):
        timed_render(renderer, scene, "hard", repeats=0)


def test_timing_renderer_uses_cpu_clocks_on_a_software_adapter() -> None:
    try:
        info = penumbra.adapter_info()
    except penumbra.GpuUnavailableError as e:
        pytest.skip(str(e))
    r = timing_renderer()
    assert not r.pass_cache
    if info["is_software"]:
        assert r.timing_source == "cpu_clock"


# --- the first command ---------------------------------------------------------


def first_command(tmp_path: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    # The README's first command at a small size: 48x48, 16 spp, one timed
    # render each, 512-texel maps (reference's 256 maps are most of the time).
    args = ["compare", "--width", "48", "--height", "48", "--spp", "16", "--repeats", "1", "--param", "map_size=512",
            "--cache-dir", str(tmp_path / "cache"), *extra]
    return subprocess.run([sys.executable, "-m", "penumbra", *args], capture_output=True, text=True, timeout=600,
                          env=without_runtime_dir(TMPDIR=str(tmp_path)), cwd=tmp_path)


@pytest.fixture(scope="module")
def needs_mitsuba_and_gpu() -> None:
    pytest.importorskip("mitsuba", reason="Mitsuba 3 is not installed")
    try:
        penumbra.adapter_info()
    except penumbra.GpuUnavailableError as e:
        pytest.skip(str(e))


def test_first_command_compares_every_method(needs_mitsuba_and_gpu: None, tmp_path: Path) -> None:
    # 64 spp (the later --spp wins): at 16 the truth's own noise (0.069 in
    # penumbra RMSE here) is larger than every good method's error, and
    # `backprojection` came 0.0008 under `reference` by that noise alone;
    # at 64 it is 0.024 (backprojection 0.031, reference 0.026).
    done = first_command(tmp_path, "-o", "compare.png", "--json", "figures.json", "--spp", "64")
    assert done.returncode == 0, done.stderr
    # Nothing on stderr but progress.
    lines = done.stderr.splitlines()
    assert lines and all(line.startswith("penumbra compare: ") for line in lines), done.stderr
    picture = tmp_path / "compare.png"
    assert picture.read_bytes()[:4] == b"\x89PNG" and picture.stat().st_size > 30_000
    figures = json.loads((tmp_path / "figures.json").read_text())
    names = [m["method"] for m in figures["methods"]]
    assert sorted(names) == sorted(penumbra.methods()) and names[-1] == "reference"
    for m in figures["methods"]:
        assert m["warm_ms"] == statistics.median(m["timed_ms"]) and m["cold_ms"] > 0
        if "map_size" in penumbra.method_info(m["method"]).defaults():
            assert m["params"]["map_size"] == 512, "--param goes to every method that takes it"
        assert np.isfinite(m["metrics"]["visibility_rmse_penumbra"])
    hard = next(m for m in figures["methods"] if m["method"] == "hard")
    assert hard["time_over_hard"] == 1.0 and figures["hard_warm_ms"] == hard["warm_ms"]
    # The printed table has a row per method and the ground truth's noise.
    for name in names:
        assert f"| {name} | " in done.stdout
    assert "*ground-truth noise*" in done.stdout and "median of 1 after a warm-up render" in done.stdout
    # reference is the yardstick: nearer the ground truth than every method
    # that approximates the light, and level with the other two exact ones
    # (raytraced, triangle_masks) to within the truth's own noise (their
    # order among themselves is that noise's: 2e-5 apart here). So is pvm,
    # whose Eq. 4.1 fraction is all but exact on this one smooth silhouette
    # (0.0088 against reference's 0.0087 with the truth at 1024 spp, the
    # README's first block): 0.0243 against 0.0247 here, the noise 0.024.
    # So is wedges since map_bound="solid" (issue 28's stop 64): its
    # coverage, held by the map's rays on both sides of the hard-shadow
    # line, came to 0.0239 (pvm 0.0233, reference 0.0247, measured).
    errors = {m["method"]: m["metrics"]["visibility_rmse_penumbra"] for m in figures["methods"]}
    noise = figures["methods"][0]["metrics"]["noise_visibility_rmse_penumbra"]
    exact = ("reference", "raytraced", "triangle_masks")
    level = ("pvm", "wedges")
    assert errors["reference"] < min(e for name, e in errors.items() if name not in (*exact, *level)), errors
    assert all(abs(errors[name] - errors["reference"]) <= noise for name in level), (errors, noise)
    assert all(abs(errors[name] - errors["reference"]) <= noise for name in exact), (errors, noise)


def test_compare_picks_methods_and_times_against_hard(needs_mitsuba_and_gpu: None, tmp_path: Path) -> None:
    done = first_command(tmp_path, "--method", "pcss", "--method", "pvm", "--json", "f.json", "-q")
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
    figures = json.loads((tmp_path / "f.json").read_text())
    assert [m["method"] for m in figures["methods"]] == ["pcss", "pvm"]
    assert figures["hard_warm_ms"] > 0, "hard is timed as the baseline without a row"
    for m in figures["methods"]:
        assert m["time_over_hard"] == pytest.approx(m["warm_ms"] / figures["hard_warm_ms"])


def test_compare_a_mesh_file_skips_methods_that_refuse_it(needs_mitsuba_and_gpu: None, tmp_path: Path) -> None:
    closed = trimesh.creation.box(extents=(1, 2, 1))
    trimesh.Trimesh(closed.vertices, closed.faces[2:], process=False).export(tmp_path / "open.obj")
    # pvm and pvmf render open meshes (docs/real_meshes.md); a parameter goes
    # to the methods that declare it (n_blur to pvmf alone); with
    # open_edges="error" pvm refuses the open mesh and is skipped.
    done = first_command(tmp_path, "--mesh", "open.obj", "--method", "pvmf", "--method", "pvm", "--param", "n_blur=0", "--json", "f.json", "-q")
    assert done.returncode == 0, done.stderr
    figures = json.loads((tmp_path / "f.json").read_text())
    assert figures["scene"] == "open.obj" and [m["method"] for m in figures["methods"]] == ["pvmf", "pvm"]
    assert figures["methods"][0]["params"]["n_blur"] == 0 and "n_blur" not in figures["methods"][1]["params"]
    done = first_command(tmp_path, "--mesh", "open.obj", "--method", "hard", "--method", "pvm", "--param", "open_edges=error", "--json", "f.json", "-q")
    assert done.returncode == 0, done.stderr
    figures = json.loads((tmp_path / "f.json").read_text())
    assert [m["method"] for m in figures["methods"]] == ["hard"]
    assert "not closed" in figures["skipped"]["pvm"] and "| pvm | skipped: " in done.stdout


def test_compare_refuses_unknown_methods_and_lone_refusals(needs_mitsuba_and_gpu: None, tmp_path: Path) -> None:
    done = first_command(tmp_path, "--method", "nope")
    assert done.returncode == 2 and "unknown method" in done.stderr
    done = first_command(tmp_path, "--param", "nonsense=1", "-q")
    assert done.returncode == 2 and "unknown parameter" in done.stderr and "Traceback" not in done.stderr


def test_compare_methods_from_python(renderer: penumbra.Renderer, needs_mitsuba_and_gpu: None, tmp_path: Path) -> None:
    scene = penumbra.scenes.get(width=32, height=32)
    lines: list[str] = []
    c = compare_methods(scene, ["hard", "pcf"], renderer=renderer, spp=16, repeats=2, cache_dir=tmp_path, progress=lines.append)
    assert [row.result.method for row in c.rows] == ["hard", "pcf"] and c.baseline is c.rows[0].timing
    assert lines and "| pcf |" in c.table()
    assert c.rows[0].result.stats["reused_passes"] == 0


# --- the smooth default sphere ------------------------------------------------


def test_default_sphere_is_smooth() -> None:
    ball = penumbra.scenes.get().meshes[1]
    assert ball.normals is not None
    radial = ball.vertices - (0.0, 1.6, 0.0)
    np.testing.assert_allclose(ball.normals, radial / np.linalg.norm(radial, axis=1, keepdims=True), atol=1e-6)
    angles = np.degrees(trimesh.Trimesh(ball.vertices, ball.faces, process=False).face_adjacency_angles)
    assert angles.max() < 1.5, "five subdivisions: the normals stay within 1.5 degrees of the faces"


def test_smooth_sphere_radiance_matches_mitsuba(renderer: penumbra.Renderer, tmp_path: Path) -> None:
    pm = pytest.importorskip("penumbra.mitsuba")
    pytest.importorskip("mitsuba", reason="Mitsuba 3 is not installed")
    # A point light: both renderers are exact there, so the sphere's shading
    # must agree within the tolerance of the unshadowed-radiance test (0.5%).
    # With the same sphere's flat faces it does not (1.2% at this size:
    # Penumbra shades a pixel by the face its centre hits, Mitsuba averages
    # the pixel), which is what the vertex normals fix.
    scene = penumbra.scenes.get(width=96, height=96, light_radius=0.0)
    result = renderer.render(scene, "hard")
    gt = pm.ground_truth(scene, spp=64, kinds=["radiance"], cache_dir=tmp_path)
    keep = (result.object_id == 1) & ~metrics.silhouette_band(result.object_id)
    lit = keep & (result.visibility == 1)
    assert lit.sum() > 200, "the sphere's lit side is in view"
    relative = metrics.rmse(result.radiance, gt.radiance, keep) / float(gt.radiance[lit].mean())
    assert relative < 0.005, f"relative RMSE {relative:.4f}"

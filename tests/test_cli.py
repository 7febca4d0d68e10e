"""The command line, run as a user would."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import penumbra
from stress_scenes import NOT_YET


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "penumbra", *args], capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module", autouse=True)
def needs_gpu() -> None:
    try:
        penumbra.adapter_info()
    except penumbra.GpuUnavailableError as e:
        pytest.skip(str(e))


def test_render_default_scene(tmp_path: Path) -> None:
    out = tmp_path / "v.npy"
    done = run("render", "--width", "64", "--height", "48", "--image", "visibility", "-o", str(out))
    assert done.returncode == 0, done.stderr
    assert "sphere_on_plane" in done.stdout and "timings" in done.stdout
    v = np.load(out)
    assert v.shape == (48, 64) and (v == 0).any() and (v == 1).any()


def test_render_png_and_params(tmp_path: Path) -> None:
    out = tmp_path / "r.png"
    done = run("render", "--scene", "cube_on_plane", "--width", "32", "--height", "32", "--param", "map_size=512", "--param", "bias=second_depth", "-o", str(out))
    assert done.returncode == 0, done.stderr
    assert '"map_size": 512' in done.stdout and '"second_depth"' in done.stdout
    assert out.read_bytes()[:4] == b"\x89PNG"


def test_render_mesh_file(tmp_path: Path) -> None:
    import trimesh

    path = tmp_path / "box.obj"
    trimesh.creation.box(extents=(1, 2, 1)).export(path)
    out = tmp_path / "m.npy"
    done = run("render", "--mesh", str(path), "--width", "32", "--height", "32", "-o", str(out))
    assert done.returncode == 0, done.stderr
    assert np.load(out).shape == (32, 32, 3)


@pytest.mark.parametrize(
    "args, words",
    [
        (["render", "--method", "nope"], "unknown method"),
        (["render", "--scene", "nope"], "unknown scene"),
        (["render", "--width", "0"], "at least 1x1"),
        (["render", "--param", "map_size=3"], "map_size"),
        (["render", "--param", "oops"], "key=value"),
        (["render", "--mesh", "/nonexistent/file.obj"], "cannot read mesh file"),
        (["render", "--light-radius", "-1"], "radius"),
        (["render", "-o", "out.bmp", "--width", "8", "--height", "8"], ".png (sRGB 8-bit), .exr (linear float), .npy (the array as is); got .bmp"),
        # Issue 33: every accepted extension named, and the render not run first.
        (["render", "-o", "x.txt", "--width", "8", "--height", "8"], "cannot write x.txt: the extension must be one of .png (sRGB 8-bit), .exr (linear float), .npy"),
        # Issue 8: more of the bad-input matrix through the command line.
        (["render", "--method", NOT_YET or "magic"], "not implemented" if NOT_YET else "unknown method"),
        (["render", "--light-radius", "nan"], "radius"),
        (["render", "--light-radius", "inf"], "radius"),
        (["render", "--height", "-3"], "height"),
        (["render", "--width", "100000", "--height", "100000"], "exceeds"),
        (["render", "--width", "8", "--height", "8", "--param", "map_size=1e9"], "map_size"),
        (["render", "--width", "8", "--height", "8", "--param", "nonsense=1"], "unknown parameter"),
        (["render", "--width", "8", "--height", "8", "--method", "pvmf", "--param", "s_e=2"], "s_e"),
        (["render", "--width", "8", "--height", "8", "--method", "pvm", "--param", "falloff=maybe"], "falloff"),
        (["render", "--width", "8", "--height", "8", "--image", "albedo"], "no image named 'albedo'"),
        (["render", "--width", "8", "--height", "8", "-o", "no/such/dir/out.png"], "no/such/dir/out.png"),
        (["render", "--mesh", "empty.obj"], "empty.obj"),
        (["render", "--mesh", "."], "cannot read mesh file"),
        (["render", "--mesh", "open.obj", "--method", "pvm", "--param", "open_edges=error", "--width", "8", "--height", "8"], "not closed"),
        (["render", "--light-radius", "50", "--width", "8", "--height", "8"], "intersects"),
    ],
)
def test_bad_arguments_exit_2_with_a_message(args: list[str], words: str, tmp_path: Path) -> None:
    import trimesh

    (tmp_path / "empty.obj").write_text("")
    closed = trimesh.creation.box()
    trimesh.Trimesh(closed.vertices, closed.faces[2:], process=False).export(tmp_path / "open.obj")
    done = subprocess.run([sys.executable, "-m", "penumbra", *args], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    assert words in done.stderr and "Traceback" not in done.stderr


@pytest.mark.parametrize(
    "args",
    [
        ["render", "--scene", "cube_on_plane", "--mesh", "x.obj"],
        ["render", "--width", "wide"],
        ["render", "--light-radius", "big"],
        ["frobnicate"],
        [],
    ],
    ids=["scene_and_mesh", "width_not_int", "radius_not_float", "unknown_command", "no_command"],
)
def test_malformed_command_lines_get_argparse_usage(args: list[str], tmp_path: Path) -> None:
    done = subprocess.run([sys.executable, "-m", "penumbra", *args], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert done.returncode == 2 and "usage: penumbra" in done.stderr and "Traceback" not in done.stderr


def test_listing_commands() -> None:
    assert run("scenes").stdout.split() == penumbra.scenes.names()
    assert "hard" in run("methods").stdout.split()
    assert '"backend"' in run("info").stdout


def test_render_defaults_to_pcss_and_says_what_it_did(tmp_path: Path) -> None:
    # Issue 23: a soft method by default, its parameters, and a warm time
    # (the median of the timed renders after a warm-up), the first render apart.
    done = run("render", "--width", "32", "--height", "32", "-o", str(tmp_path / "r.png"))
    assert done.returncode == 0, done.stderr
    assert "method pcss" in done.stdout and '"filter_samples": 6' in done.stdout
    assert "warm time" in done.stdout and "median of 5 after a warm-up render" in done.stdout and "first render" in done.stdout
    once = run("render", "--width", "32", "--height", "32", "--repeats", "0", "-o", str(tmp_path / "r.png"))
    assert once.returncode == 0 and "warm time" not in once.stdout and "the first" in once.stdout

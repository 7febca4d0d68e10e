"""The command line, run as a user would."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import penumbra


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
        (["render", "-o", "out.bmp", "--width", "8", "--height", "8"], ".png or .exr"),
    ],
)
def test_bad_arguments_exit_2_with_a_message(args: list[str], words: str, tmp_path: Path) -> None:
    done = subprocess.run([sys.executable, "-m", "penumbra", *args], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    assert words in done.stderr and "Traceback" not in done.stderr


def test_listing_commands() -> None:
    assert run("scenes").stdout.split() == penumbra.scenes.names()
    assert "hard" in run("methods").stdout.split()
    assert '"backend"' in run("info").stdout

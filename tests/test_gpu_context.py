"""Adapter choice through WGPU_BACKEND and WGPU_ADAPTER_NAME, and the error
when there is no adapter. Run in subprocesses: the environment is read when a
renderer is created."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

import penumbra

PROBE = """
import penumbra
try:
    r = penumbra.Renderer()
    print("OK", r.adapter_info["name"], r.adapter_info["backend"])
except penumbra.GpuUnavailableError as e:
    print("UNAVAILABLE", e)
"""


def probe(**env: str) -> str:
    done = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, timeout=120, env={**os.environ, **env})
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


@pytest.fixture(scope="module")
def adapter() -> dict:
    try:
        return penumbra.adapter_info()
    except penumbra.GpuUnavailableError as e:
        pytest.skip(str(e))


def test_adapter_info_describes_the_choice(adapter: dict) -> None:
    assert {"name", "backend", "device_type", "driver", "timestamp_queries", "is_software"} <= set(adapter)
    assert adapter["is_software"] == (adapter["device_type"] == "Cpu")


def test_adapter_name_filter_selects_by_substring(adapter: dict) -> None:
    assert probe(WGPU_ADAPTER_NAME=adapter["name"][:5].upper()).startswith(f"OK {adapter['name']}")


def test_unknown_adapter_name_is_a_clear_error(adapter: dict) -> None:
    out = probe(WGPU_ADAPTER_NAME="no-such-gpu-anywhere")
    assert out.startswith("UNAVAILABLE") and "WGPU_ADAPTER_NAME" in out and adapter["name"] in out


def test_no_adapter_names_the_driver_package() -> None:
    # A backend this platform does not have leaves no adapter at all.
    backend = "metal" if sys.platform != "darwin" else "dx12"
    out = probe(WGPU_BACKEND=backend)
    assert out.startswith("UNAVAILABLE") and "mesa-vulkan-drivers" in out


def test_backend_variable_is_honoured(adapter: dict) -> None:
    assert probe(WGPU_BACKEND=adapter["backend"]).startswith("OK")

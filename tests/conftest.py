"""Shared fixtures: one renderer per session (device creation on lavapipe is
slow), skipped with the reason when no GPU adapter exists."""

from __future__ import annotations

import os

import pytest

import penumbra
from stress_scenes import new_renderer


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Tests of method `raytraced` (by id) skip, with the reason, on an adapter
    without ray queries; not in CI, where scripts/setup.sh installs them."""
    try:
        info = penumbra.adapter_info()
    except penumbra.GpuUnavailableError:
        return
    if info.get("ray_queries") or os.environ.get("CI"):
        return
    skip = pytest.mark.skip(reason=f"method raytraced needs ray queries, which adapter {info['name']} ({info['driver_info']}) lacks")
    for item in items:
        if "raytraced" in item.nodeid.split("::")[-1]:
            item.add_marker(skip)


@pytest.fixture(scope="session")
def renderer() -> penumbra.Renderer:
    return new_renderer()

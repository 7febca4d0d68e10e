"""Shared fixtures: one renderer per session (device creation on lavapipe is
slow), skipped with the reason when no GPU adapter exists."""

from __future__ import annotations

import pytest

import penumbra


@pytest.fixture(scope="session")
def renderer() -> penumbra.Renderer:
    try:
        return penumbra.Renderer()
    except penumbra.GpuUnavailableError as e:
        pytest.skip(f"no GPU adapter: {e}")

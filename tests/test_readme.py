"""The README's Python example runs as written."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import penumbra

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_python_example_runs(renderer: penumbra.Renderer, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    assert blocks, "the README has a Python example"
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    exec(compile(blocks[0], "README.md", "exec"), namespace)
    result = namespace["result"]
    assert (tmp_path / "out.png").exists()
    assert result.radiance.shape == (256, 256, 3) and np.isfinite(result.radiance).all()
    assert {1, 2} <= set(np.unique(result.object_id)), "both casters are in view"
    assert (result.visibility[result.object_id == 0] == 0).any(), "they cast shadows"


def test_parameter_page_is_current() -> None:
    """docs/parameters.md is what the registry declares today."""
    from penumbra.cli import parameters_markdown

    page = README.parent / "docs" / "parameters.md"
    assert page.read_text() == parameters_markdown(), "regenerate: python -m penumbra methods --markdown > docs/parameters.md"

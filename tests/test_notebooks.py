"""The notebooks (issue 9): committed with their outputs stripped, and each
runs top to bottom at small size (nbclient, in pytest, so in scripts/test.sh)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

import penumbra

NOTEBOOKS = sorted((Path(__file__).resolve().parents[1] / "notebooks").glob("*.ipynb"))
# Small enough for CI's two cores: images, ground-truth samples per pixel.
CI_SIZE, CI_SPP = "32", "16"


@pytest.fixture(scope="module")
def ground_truth_cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``$PENUMBRA_CACHE_DIR`` when set (a CI cache that outlives the run), else
    a temporary folder the three notebooks share."""
    root = os.environ.get("PENUMBRA_CACHE_DIR")
    return Path(root) if root else tmp_path_factory.mktemp("penumbra-cache")


def test_the_three_notebooks_exist() -> None:
    assert [p.name for p in NOTEBOOKS] == ["01_light_radius.ipynb", "02_pvmf_parameters.ipynb", "03_time_vs_error.ipynb"]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_outputs_are_stripped(path: Path) -> None:
    """What `nbstripout` would leave: no outputs, no execution counts, no
    per-cell or widget metadata."""
    book = json.loads(path.read_text())
    assert set(book["metadata"]) <= {"kernelspec", "language_info"}, path.name
    for i, cell in enumerate(book["cells"]):
        where = f"{path.name} cell {i}"
        assert cell.get("metadata", {}) == {}, where
        if cell["cell_type"] == "code":
            assert cell["outputs"] == [], f"{where} has outputs: strip them (e.g. nbstripout)"
            assert cell["execution_count"] is None, where


@pytest.mark.gpu
@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_runs(path: Path, monkeypatch: pytest.MonkeyPatch, ground_truth_cache: Path) -> None:
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    try:
        penumbra.adapter_info()
    except penumbra.GpuUnavailableError as e:
        pytest.skip(f"no GPU adapter: {e}")
    # The kernel inherits the environment: small sizes, a shared ground-truth cache;
    # figures go inline (matplotlib-inline), so no display is needed.
    monkeypatch.setenv("PENUMBRA_NOTEBOOK_SIZE", CI_SIZE)
    monkeypatch.setenv("PENUMBRA_NOTEBOOK_SPP", CI_SPP)
    monkeypatch.setenv("PENUMBRA_CACHE_DIR", str(ground_truth_cache))
    monkeypatch.delenv("PENUMBRA_BENCHMARK_CSV", raising=False)
    monkeypatch.delenv("MPLBACKEND", raising=False)
    book = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(book, timeout=240, kernel_name="python3", resources={"metadata": {"path": str(path.parent)}})
    client.execute()
    errors = [o for c in book.cells if c.cell_type == "code" for o in c.outputs if o.output_type == "error"]
    assert not errors
    images = [o for c in book.cells if c.cell_type == "code" for o in c.outputs if "image/png" in o.get("data", {})]
    assert images, f"{path.name} draws its figures"

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


ROOT = README.parent
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")


def _slug(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def _anchors(path: Path) -> set[str]:
    text = re.sub(r"```.*?```", "", path.read_text(), flags=re.S)
    return {_slug(m.group(2)) for m in re.finditer(r"^(#+)\s+(.*)$", text, flags=re.M)}


def _documents() -> list[Path]:
    return [README, *sorted((ROOT / "docs").rglob("*.md"))]


@pytest.mark.parametrize("doc", _documents(), ids=lambda p: str(p.relative_to(ROOT)))
def test_relative_links_resolve(doc: Path) -> None:
    # Every relative link and image of the README and docs/ names a file of
    # the repository (and, for a Markdown file, a heading that exists).
    text = re.sub(r"```.*?```", "", doc.read_text(), flags=re.S)
    text = re.sub(r"`[^`\n]*`", "", text)
    broken = []
    for target in LINK.findall(text):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target):  # http:, https:, mailto:
            continue
        path, _, anchor = target.partition("#")
        resolved = (doc.parent / path).resolve() if path else doc
        if not resolved.exists() or ROOT not in [resolved, *resolved.parents]:
            broken.append(target)
        elif anchor and resolved.suffix == ".md" and anchor not in _anchors(resolved):
            broken.append(target)
    assert not broken, f"{doc.relative_to(ROOT)}: broken links {broken}"


def test_readme_is_a_front_page() -> None:
    text = README.read_text()
    assert len(text.splitlines()) <= 250
    # Its first command, and the picture that command writes, committed.
    assert "bash scripts/setup.sh && python3 -m penumbra compare -o compare.png" in text
    assert "](docs/images/compare.png)" in text and (ROOT / "docs" / "images" / "compare.png").exists()
    # Every implemented method has a row linked to its page.
    for method in penumbra.methods():
        assert f"[`{method}`](docs/methods/{method}.md)" in text, method


def test_parameter_page_is_current() -> None:
    """docs/parameters.md is what the registry declares today."""
    from penumbra.cli import parameters_markdown

    page = ROOT / "docs" / "parameters.md"
    assert page.read_text() == parameters_markdown(), "regenerate: python -m penumbra methods --markdown > docs/parameters.md"


def test_the_method_table_and_advice_come_from_the_committed_bench_run() -> None:
    # The README's block is what `python -m penumbra.bench.readme` writes from
    # benchmarks/results/bench/results.csv (issue 29): rerun it after a bench run.
    from penumbra.bench import readme

    text = README.read_text()
    assert readme.START in text and readme.END in text, "the README keeps its generated block"
    assert readme.update(text, readme.load_rows(readme.RESULTS)) == text, "the README's method table differs from the committed bench results: run python -m penumbra.bench.readme"
    for method in penumbra.methods():
        assert f"[`{method}`](docs/methods/{method}.md)" in text, f"{method} has its row"

"""Every Python snippet in README.md and docs/*.md runs as written (each ```python block of a
page runs in order, in one namespace, in a fresh directory), so none can go stale."""
import re
from pathlib import Path

import matplotlib
import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md"] + sorted((ROOT / "docs").glob("*.md"))
BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)


def _pages_with_snippets():
    return [p for p in PAGES if BLOCK.search(p.read_text())]


def test_the_readme_has_snippets():
    assert ROOT / "README.md" in _pages_with_snippets()


@pytest.mark.parametrize("page", _pages_with_snippets(), ids=lambda p: p.name)
def test_snippets_run_as_written(page, tmp_path, monkeypatch):
    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "__snippet__"}
    for i, block in enumerate(BLOCK.findall(page.read_text())):
        code = compile(block, f"{page.name}, snippet {i + 1}", "exec")
        exec(code, namespace)
    import matplotlib.pyplot as plt
    plt.close("all")

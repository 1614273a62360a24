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


TOML = re.compile(r"^```toml\n(.*?)^```", re.S | re.M)


@pytest.mark.parametrize("page", [p for p in PAGES if TOML.search(p.read_text())],
                         ids=lambda p: p.name)
def test_scene_snippets_load_and_run(page, tmp_path):
    """Every ```toml block of a page is a scene that loads and runs two steps as written."""
    from dttmm import simulate
    from dttmm.interfaces.scene import load_scene
    for i, block in enumerate(TOML.findall(page.read_text())):
        path = tmp_path / f"{page.stem}_{i + 1}.toml"
        path.write_text(block)
        scene = load_scene(path)
        result = simulate(scene.model, 2 * scene.run.get("dt", 1e-3),
                          scene.run.get("dt", 1e-3))
        assert result.t.size == 3

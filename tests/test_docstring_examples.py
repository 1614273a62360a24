"""Every docstring example runs (issue 65, item 7): the doctests of every module of the package
(its kernels aside, which hold none), in a fresh directory; ``# doctest: +SKIP`` marks the lines
that need a file or a model from elsewhere."""
import doctest
import importlib
import pkgutil

import pytest

import dttmm

MODULES = sorted(m.name for m in pkgutil.walk_packages(dttmm.__path__, "dttmm.")
                 if ".kernels" not in m.name and not m.name.endswith("__main__"))


def _examples():
    finder = doctest.DocTestFinder(exclude_empty=True)
    found = []
    for name in MODULES:
        for test in finder.find(importlib.import_module(name)):
            if test.examples:
                found.append(test)
    return found


EXAMPLES = _examples()


def test_the_package_has_examples():
    assert len(EXAMPLES) >= 30


@pytest.mark.parametrize("test", EXAMPLES, ids=[t.name for t in EXAMPLES])
def test_docstring_example_runs(test, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    report = []
    result = runner.run(test, out=report.append)
    assert result.failed == 0, "".join(report)


def test_the_close_example_is_the_four_bar_it_describes():
    """System.close's example (before issue 65 it rooted both cranks at the ground's one point,
    left one out of the loop, and started open): every body in the loop, closed at t = 0, one
    degree of freedom."""
    namespace = {}
    for example in doctest.DocTestParser().get_examples(dttmm.System.close.__doc__):
        exec(example.source, namespace)
    model = namespace["model"]
    assert dttmm.loop_residuals(model)[0].max() < 1e-12
    assert "mobility 1 as a rigid mechanism" in model.describe()
    assert len(model.body_names) == 3

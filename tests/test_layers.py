"""The package in layers (docs/README.md, "Layout"): no import circle, every module imports only
from its own folder and from the folders below it, the kernels import nothing of the Python
layer above them, and no module grows past about 800 lines."""
import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent.parent / "dttmm"

# the folders of dttmm/ bottom up (docs/README.md, "Layout"): a module imports from its own folder
# or from a folder of a lower rank, never from one of its own rank or above (the solving layer
# and the Newton-Euler reference beside it import nothing from each other)
RANKS = {"vectors": 0,          # vectors.py, numpy helpers below everything
         "elements": 1,         # the element classes and their kinds
         "kernels": 2,          # numba on flat arrays
         "model": 3,            # what is simulated
         "results": 4,          # what a run gives back, filled by the solving layer
         "solving": 5, "reference": 5,
         "interfaces": 6,       # scenes, the command line, describe, sweeps
         "__init__": 7, "__main__": 7}   # the package's face and python -m dttmm

def _modules():
    out = {}
    for path in PACKAGE.rglob("*.py"):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = path
    return out


def _imports(modules):
    """Every module's imports of the package's modules, at any depth of its code (a function's
    import counts: it runs the same way)."""
    graph = {}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
        found = set()
        for node in ast.walk(ast.parse(path.read_text())):
            targets = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    up = package.split(".")[:len(package.split(".")) - node.level + 1]
                    base = ".".join(up + ([node.module] if node.module else []))
                targets = [f"{base}.{a.name}" for a in node.names] + [base]
            for target in targets:
                while target and target not in modules:
                    target = target.rpartition(".")[0]
                if target and target not in (name, "dttmm"):
                    found.add(target)
        graph[name] = found
    return graph


def _circles(graph):
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(component))
    for v in graph:
        if v not in index:
            visit(v)
    return out


def test_no_module_imports_another_that_imports_it_back():
    graph = _imports(_modules())
    assert _circles(graph) == []


def _folder(name):
    """A module's folder under dttmm/ (a module at the top: its own name)."""
    parts = name.split(".")
    return "__init__" if len(parts) == 1 else parts[1]


def test_every_module_stands_in_a_layer():
    unplaced = sorted(n for n in _modules() if _folder(n) not in RANKS)
    assert not unplaced, f"modules in no folder of RANKS: {unplaced}"


def test_every_import_runs_down_the_layers():
    graph = _imports(_modules())
    up = [f"{name} ({_folder(name)}) imports {target} ({_folder(target)})"
          for name, targets in sorted(graph.items()) for target in sorted(targets)
          if _folder(target) != _folder(name)
          and RANKS[_folder(target)] >= RANKS[_folder(name)]]
    assert not up, "\n".join(up)


def test_kernels_import_only_kernels_and_elements():
    graph = _imports(_modules())
    for name, targets in graph.items():
        if name.startswith("dttmm.kernels"):
            above = [t for t in targets if not t.startswith(("dttmm.kernels", "dttmm.elements"))]
            assert not above, f"{name} imports {above}"


def test_elements_import_nothing_above_them():
    """(but vectors.py, numpy helpers below everything)"""
    graph = _imports(_modules())
    for name, targets in graph.items():
        if name.startswith("dttmm.elements"):
            above = [t for t in targets
                     if not t.startswith("dttmm.elements") and t != "dttmm.vectors"]
            assert not above, f"{name} imports {above}"


def test_no_module_grows_past_about_800_lines():
    long = {str(p.relative_to(PACKAGE)) for p in PACKAGE.rglob("*.py")
            if len(p.read_text().splitlines()) > 820}
    assert not long, sorted(long)

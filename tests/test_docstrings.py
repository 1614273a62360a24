"""The public API is documented: numpydoc sections and every argument named in the docstring."""
import ast
import inspect
import re
import textwrap

import pytest

import dttmm
from dttmm.interfaces import scene
from dttmm.model import profiles

def _public():
    """(name, object) of every class and function in dttmm.__all__."""
    out = []
    for name in dttmm.__all__:
        if name == "__version__":
            continue
        obj = getattr(dttmm, name)
        if inspect.isclass(obj) or inspect.isfunction(obj):
            out.append((name, obj))
    return out


# the public methods and module functions the docs name (beyond dttmm.__all__)
METHODS = [
    ("System.add", dttmm.System.add), ("System.build", dttmm.System.build),
    ("PrescribedMotion.spin_about_axis", dttmm.PrescribedMotion.spin_about_axis),
    ("Result.replace", dttmm.Result.replace), ("Result.save_npz", dttmm.Result.save_npz),
    ("Result.load_npz", dttmm.Result.load_npz), ("Result.save_csv", dttmm.Result.save_csv),
    ("Result.plot_positions", dttmm.Result.plot_positions),
    ("Result.plot_angles", dttmm.Result.plot_angles),
    ("Result.plot_energy", dttmm.Result.plot_energy),
    ("Result.plot_joints", dttmm.Result.plot_joints),
    ("Result.plot_modal", dttmm.Result.plot_modal),
    ("SweepTable.save_csv", dttmm.SweepTable.save_csv),
    ("Checkpoint.save", dttmm.Checkpoint.save), ("Checkpoint.load", dttmm.Checkpoint.load),
    ("scene.load_scene", scene.load_scene), ("scene.save_scene", scene.save_scene),
    ("scene.scene_of", scene.scene_of), ("profiles.profile", profiles.profile),
    ("profiles.Profile", profiles.Profile), ("profiles.ProfileForce", profiles.ProfileForce),
]


def _docstring(obj):
    """A class's own docstring, or its __init__'s; a function's docstring."""
    if inspect.isclass(obj):
        doc = obj.__doc__ or ""
        if "Parameters" not in doc and obj.__init__ is not object.__init__:
            doc = (obj.__init__.__doc__ or "") + "\n" + doc
        return doc
    return obj.__doc__ or ""


def _arguments(obj):
    """Every parameter of the signature (classes: the constructor's) but self and cls, and
    whether there is any argument at all (*args and **kwargs included)."""
    params = list(inspect.signature(obj).parameters.values())
    if params and params[0].name in ("self", "cls"):
        params = params[1:]
    named = [p.name for p in params
             if p.kind not in (inspect.Parameter.VAR_POSITIONAL, inspect.Parameter.VAR_KEYWORD)]
    return named, bool(params)


def _returns_value(func):
    """Whether a function's own body has a `return <value>` (nested functions left out)."""
    func = inspect.unwrap(getattr(func, "__func__", func))
    tree = ast.parse(textwrap.dedent(inspect.getsource(func)))
    node = tree.body[0]

    def visit(n):
        for child in ast.iter_child_nodes(n):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda,
                                  ast.ClassDef)):
                continue
            if isinstance(child, ast.Return) and child.value is not None:
                return True
            if visit(child):
                return True
        return False

    return visit(node)


def _check(name, obj):
    doc = _docstring(obj)
    assert doc.strip(), f"{name} has no docstring"
    named, takes_arguments = _arguments(obj)
    if takes_arguments:
        assert "Parameters" in doc, f"{name}: its docstring has no Parameters section"
    if not inspect.isclass(obj) and _returns_value(obj):
        assert "Returns" in doc, f"{name} returns a value; its docstring has no Returns section"
    missing = [p for p in named if not re.search(rf"(?<![\w.]){re.escape(p)}(?!\w)", doc)]
    assert not missing, f"{name}: its docstring does not name the arguments {missing}"


def test_public_names_are_listed():
    names = [name for name, _ in _public()]
    assert "simulate" in names and "RigidBody" in names and "sweep" in names


@pytest.mark.parametrize("name, obj", [pytest.param(n, o, id=n) for n, o in _public()])
def test_public_docstring(name, obj):
    _check(name, obj)


@pytest.mark.parametrize("name, obj", [pytest.param(n, o, id=n) for n, o in METHODS])
def test_public_method_docstring(name, obj):
    _check(name, obj)


def test_the_check_finds_what_is_missing():
    def undocumented(mass, length=1.0):
        """Make a thing.

        Parameters
        ----------
        mass : float
            kg.
        """
        return mass * length

    with pytest.raises(AssertionError, match="Returns"):
        _check("undocumented", undocumented)
    undocumented.__doc__ += "\n    Returns\n    -------\n    float\n"
    with pytest.raises(AssertionError, match=r"\['length'\]"):
        _check("undocumented", undocumented)

"""One compiled core for every kind of model (issue 66): `dttmm compile`, then no model compiles
anything, not even from a read-only install."""
import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import dttmm
from dttmm import (BallJoint, ElasticHinge, EulerBernoulliBeam, FixedHinge, RevoluteJoint,
                   RigidBody, StrainRod, System, build_chain, simulate)
from dttmm.model.chains import arm, three_pendulum, unit_link
from dttmm.kernels import python_twin
from dttmm.kernels.stepping import step as kstep
from dttmm.kernels.stepping.loop import _skeleton
from dttmm.model.mechanisms import n_four_bar, slider_crank

# the kinds of model the new user met, as a script a fresh process runs
SESSION = '''
import numpy as np
import dttmm
from dttmm import (ElasticHinge, EulerBernoulliBeam, FixedHinge, BallJoint, RevoluteJoint,
                   RigidBody, StrainRod, System, build_chain, simulate)
from dttmm.model.chains import arm, unit_link
from dttmm.model.mechanisms import n_four_bar, slider_crank
from numba.core import event

compiled = []


class Count(event.Listener):
    def on_start(self, e):
        fn = getattr(e.data.get("dispatcher"), "py_func", None)
        if getattr(fn, "__module__", "").startswith("dttmm"):
            compiled.append(fn.__qualname__)

    def on_end(self, e):
        pass


event.register("numba:compile", Count())
simulate(arm(), 2e-3, 1e-3)
simulate(slider_crank(), 2e-3, 1e-3)
simulate(n_four_bar(3), 2e-3, 1e-3)
beam = EulerBernoulliBeam(length=1.0, bending_stiffness=175.0, density=7850.0, area=1e-4,
                          polar_inertia_per_length=1.3e-4)
tip = RigidBody(mass=0.2, inertia=[1e-6] * 3, inertia_about="mass_center")
cantilever = build_chain([FixedHinge(), beam, FixedHinge(), tip], gravity=[0.0, -9.81, 0.0])
dttmm.static_equilibrium(cantilever)
simulate(cantilever, 2e-3, 1e-4)
parts = []
for i in range(3):
    parts += [ElasticHinge(1e5, 1e3), unit_link(name=f"l{i}")]
simulate(build_chain(parts, gravity=[0, -9.81, 0]), 2e-3, 1e-3)
s = System(gravity=[0, -9.81, 0])
s.add(unit_link(name="a"), BallJoint(name="j"))
s.add(unit_link(name="b"), FixedHinge(), parent="a")
s.add(unit_link(name="c"), FixedHinge(), parent="a")
simulate(s.build(), 2e-3, 1e-3)
rod = StrainRod(length=0.3, bending_stiffness=50.0, mass_per_length=1.0,
                polar_inertia_per_length=1e-4)
simulate(build_chain([RevoluteJoint(axis=[0, 0, 1.0]), rod], gravity=[0, -9.81, 0]), 2e-3, 1e-3)
print("COMPILED", compiled)
'''


def _models():
    """Seven kinds of model: rigid joints, a loop of prismatic and revolute joints, a loop of
    ball joints, welded beams with a tip body, elastic hinges, a tree of fixed hinges on a ball,
    a strain rod behind a revolute joint."""
    beam = EulerBernoulliBeam(length=1.0, bending_stiffness=175.0, density=7850.0, area=1e-4,
                              polar_inertia_per_length=1.3e-4)
    tip = RigidBody(mass=0.2, inertia=[1e-6] * 3, inertia_about="mass_center")
    parts = []
    for i in range(3):
        parts += [ElasticHinge(1e5, 1e3), unit_link(name=f"l{i}")]
    tree = System(gravity=[0, -9.81, 0])
    tree.add(unit_link(name="a"), BallJoint(name="j"))
    tree.add(unit_link(name="b"), FixedHinge(), parent="a")
    tree.add(unit_link(name="c"), FixedHinge(), parent="a")
    rod = StrainRod(length=0.3, bending_stiffness=50.0, mass_per_length=1.0,
                    polar_inertia_per_length=1e-4)
    return [arm(), slider_crank(), n_four_bar(3),
            build_chain([FixedHinge(), beam, FixedHinge(), tip], gravity=[0.0, -9.81, 0.0]),
            build_chain(parts, gravity=[0, -9.81, 0]), tree.build(),
            build_chain([RevoluteJoint(axis=[0, 0, 1.0]), rod], gravity=[0, -9.81, 0])]


# (runs of two steps, to type the kernels, not to resolve the cantilever's highest mode)
@pytest.mark.filterwarnings("ignore::dttmm.UnresolvedMotionWarning")
def test_every_kind_of_model_runs_one_compiled_core():
    """The general loop's skeleton and its start take arguments of one type for every kind of
    model, so numba compiles each once (a second signature is a second compile, a minute or
    more cold).  Each model also runs (finite, moving)."""
    for model in _models():
        res = simulate(model, 2e-3, 1e-3)
        assert np.all(np.isfinite(res.position_output))
        dttmm.forward_dynamics(model, 0.0)
    skeleton = _skeleton(kstep.GeneralLoop)
    assert len(skeleton.signatures) == 1, skeleton.signatures
    start = python_twin(kstep.initial_accelerations)
    assert len(start.signatures) <= 1, start.signatures


def _read_only(tree):
    for path in tree.rglob("*"):
        mode = path.stat().st_mode
        path.chmod(mode & ~(stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH))
    tree.chmod(tree.stat().st_mode & ~(stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH))


def _writable(tree):
    tree.chmod(tree.stat().st_mode | stat.S_IWUSR)
    for path in tree.rglob("*"):
        path.chmod(path.stat().st_mode | stat.S_IWUSR)


def test_after_dttmm_compile_a_read_only_install_compiles_nothing(tmp_path):
    """`dttmm compile` (every family; quick where the suite compiled them already), then the
    package copied with its caches and made read-only, as a lab's shared install: a new process
    runs seven kinds of model, statics among them, and numba compiles none of dttmm's
    functions.  (Counted by numba's compile events, which hold whoever runs the test: as root,
    permissions would not stop a write.)"""
    done = subprocess.run([sys.executable, "-m", "dttmm", "compile", "--no-progress"],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "cache:" in done.stdout
    installed = Path(dttmm.__file__).parent
    copy = tmp_path / "site" / "dttmm"
    shutil.copytree(installed, copy)            # (copy2: the sources' times, as numba keys)
    _read_only(tmp_path / "site")
    try:
        env = dict(os.environ, PYTHONPATH=str(tmp_path / "site"))
        env.pop("NUMBA_CACHE_DIR", None)
        run = subprocess.run([sys.executable, "-c", SESSION], capture_output=True, text=True,
                             env=env, cwd=tmp_path)
    finally:
        _writable(tmp_path / "site")
    assert run.returncode == 0, run.stderr[-2000:]
    line = [x for x in run.stdout.splitlines() if x.startswith("COMPILED")][0]
    assert line == "COMPILED []", line


# every version numba holds of dttmm's kernels in a process (each kernel module's dispatchers,
# the skeletons, the Python layer's twins)
VERSIONS = """
import importlib, pkgutil
import dttmm.kernels as kernels
from dttmm.kernels.stepping import loop
from numba.core.dispatcher import Dispatcher


def versions():
    found = set(kernels.PYTHON_CALLED.values()) | set(loop._SKELETONS.values())
    for info in pkgutil.walk_packages(kernels.__path__, "dttmm.kernels."):
        module = importlib.import_module(info.name)
        found |= {v for v in vars(module).values() if isinstance(v, Dispatcher)}
    return {(d.py_func.__qualname__, str(s)) for d in found for s in d.signatures}
"""

# after the session: statics, linear models, forward dynamics from a given state, a rod's
# describe, and the derived fields of a loop's result (its closing joints' energies)
MORE = """
from dttmm.model.mechanisms import slider_crank
crank = slider_crank()
dttmm.static_equilibrium(crank)
dttmm.linearize(crank)
res = simulate(crank, 2e-3, 1e-3, hold_energy=True)
res.kinetic, res.position_output
dttmm.forward_dynamics(crank, res.t[-1], state=res.state(-1))
rod_model = build_chain([RevoluteJoint(axis=[0, 0, 1.0]), rod], gravity=[0, -9.81, 0])
rod_model.describe()
simulate(rod_model, 2e-3, 1e-3).position_output
"""


@pytest.mark.filterwarnings("ignore::dttmm.UnresolvedMotionWarning")
def test_the_core_is_whole_after_its_first_use():
    """solving/core.py lists the core's kernels the Python layer calls itself, which the core's
    first use on an install compiles with the skeleton.  A process that takes that path (its
    first use forced) for the arm: after it, the issue's session of other kinds of model, their
    statics, linear models and forward dynamics, and their results' derived fields add no
    version to any kernel (on a fresh install each would be a compile: the slider-crank's
    4.8 s before the list)."""
    first = """
from dttmm.solving import core
core.compiled_here = lambda: True
from dttmm.model.chains import arm
dttmm.simulate(arm(), 2e-3, 1e-3)
before = versions()
"""
    session = SESSION.replace('print("COMPILED", compiled)', "")
    script = ("import dttmm\n" + VERSIONS + first + session + MORE
              + "print('ADDED', sorted(versions() - before))\n")
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-2000:]
    line = [x for x in run.stdout.splitlines() if x.startswith("ADDED")][0]
    assert line == "ADDED []", line[:3000]


@pytest.mark.parametrize("model", [three_pendulum])
def test_describe_says_the_core_is_compiled_once(model):
    text = model().describe()
    assert "compiled once per install" in text


def _first_use_calls(model):
    """(helper_calls, main_calls, python_calls) of solving/core.py with the types of `model`'s
    run (its consistent start's loop and Run)."""
    from dttmm.solving import core
    seen = {}
    complete = core.complete

    def spy(params, loops, state, loop=None, run=None):
        seen.update(params=params, loops=loops, state=state, loop=loop, run=run)
        complete(params, loops, state, loop, run)

    core.complete = spy
    try:
        simulate(model, 2e-3, 1e-3)
    finally:
        core.complete = complete
    return (core.helper_calls(seen["loop"], seen["run"]),
            core.main_calls(seen["loop"], seen["run"]),
            core.python_calls(seen["params"], seen["loops"], seen["state"]))


@pytest.mark.parametrize("model", [arm, lambda: n_four_bar(2)], ids=["arm", "four_bar"])
def test_the_first_uses_two_shares_are_the_versions_the_skeleton_calls(model):
    """The core's first use compiles in two processes (solving/core.py): each kernel of the
    helper's share and of this process's is compiled by its argument types, so the skeleton,
    compiled after, must call it with exactly those, or it compiles it again.  numba's cache
    (compiled by the skeleton here, or by the split itself on a fresh install) holds that version
    of each, and for the four kernels the shares add, that version alone."""
    helper, main, python = _first_use_calls(model())
    for kernel, types in helper + main + python:
        name = kernel.py_func.__name__
        if kernel._cache is None or not hasattr(kernel._cache, "_cache_file"):
            pytest.skip("numba's cache is off")
        assert kernel._cache.load_overload(types, kernel.targetctx) is not None, name
        if (kernel, types) in helper + main:
            assert len(kernel._cache._cache_file._load_index()) == 1, name


def test_the_helper_process_compiles_what_it_is_sent():
    """The helper (solving/core.py::_start_helper) starts, reads the pickled calls and compiles
    (here: loads) them; it exits cleanly."""
    from dttmm.solving import core
    helper, _, _ = _first_use_calls(arm())
    process = core._start_helper(helper)
    assert process is not None
    assert process.wait(timeout=300) == 0

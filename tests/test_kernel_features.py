"""Kernels compiled for what a model uses (dttmm/kernels/features.py; docs/solver.md, "Compile
time"): the features a model's kernels get, the code a copy drops before numba types it, the
fields a copy takes as None, and the refusal where a copy meets a kind it was not compiled for."""
import os
import subprocess
import sys
from importlib import resources

import numpy as np
import pytest
from numba.core import analysis, compiler, ir, ir_utils, types
from numba.core.dispatcher import Dispatcher

from dttmm import chains, solver
from dttmm.kernels.stepping import em_step
from dttmm.kernels import features as kf
from dttmm.kernels.stepping import loop as kloop
from dttmm.kernels.stepping import step as kstep
from dttmm.scene import load_scene


@pytest.fixture(autouse=True)
def copies_on(monkeypatch):
    """This file's tests take the kernels' copies (the suite's conftest turns them off)."""
    monkeypatch.setattr(kf, "SPECIALIZE", True)


def _scene_model(name):
    return load_scene(resources.files("dttmm") / "scenes" / f"{name}.toml").model


def _features(model, method="riccati", stations=False):
    km, _ = solver.kernel_model(model)
    return solver.kernel_features(km, solver._mode(km, method, False), stations)


@pytest.mark.parametrize("scene, expected", [
    ("arm", {"SWEEP_JOINTS"}),
    ("flexible_arm", {"SWEEP_JOINTS", "HAS_BEAMS"}),
    ("four_bar", {"SWEEP_JOINTS", "HAS_LOOPS"}),
    ("flexible_slider_crank", {"SWEEP_JOINTS", "HAS_LOOPS", "HAS_BEAMS"}),
    ("tree", {"SWEEP_TREE"}),
])
def test_a_scene_gets_the_features_it_uses(scene, expected):
    assert _features(_scene_model(scene)) == expected


def test_the_sweep_follows_the_method_and_the_scheme_adds_the_stations():
    chain = chains.rigid_chain(3)
    assert _features(chain) == {"SWEEP_REDUCED"}
    assert _features(chain, "direct") == {"SWEEP_DIRECT_REDUCED"}
    assert _features(chain, stations=True) == {"SWEEP_REDUCED", "HAS_STATION_HISTORIES"}


def _kept_globals(kernel):
    """The njit kernels a kernel's code still names after numba's dead-branch pruning (the
    pass numba runs before typing), and the flags it reads."""
    func_ir = compiler.run_frontend(kernel.py_func)
    analysis.dead_branch_prune(func_ir, [types.int64] * func_ir.arg_count)
    func_ir.blocks = ir_utils.simplify_CFG(func_ir.blocks)
    named = set()
    for block in func_ir.blocks.values():
        for stmt in block.body:
            if isinstance(stmt, ir.Assign) and isinstance(stmt.value, (ir.Global, ir.FreeVar)):
                value = stmt.value.value
                if isinstance(value, Dispatcher):
                    named.add(value.py_func.__name__.split("__")[0])
    return named


def test_a_copy_drops_the_sweeps_and_kinds_the_model_does_not_use():
    solve = kf.specialized(kstep.solve_step, {"SWEEP_JOINTS"})
    assert "riccati_tree_full" in _kept_globals(solve)
    assert not {"riccati_full", "direct_full", "riccati_reduced", "direct_reduced",
                "_solve_tree"} & _kept_globals(solve)
    assert {"riccati_full", "direct_full", "riccati_reduced", "direct_reduced",
            "_solve_tree"} <= _kept_globals(kstep.solve_step)    # (every flag on: all of them)
    build = kf.specialized(kstep._build_elements, {"SWEEP_JOINTS"})
    assert "joint_linearization" in _kept_globals(build)
    assert not {"beam_transfer", "elastic_hinge_transfer",
                "station_history_correction"} & _kept_globals(build)
    start = kf.specialized(kstep.initial_accelerations, {"SWEEP_JOINTS"})
    assert not {"solve_with_loops", "tree_points", "elastic_hinge_loads"} & _kept_globals(start)
    with_loops = kf.specialized(kstep.initial_accelerations, {"SWEEP_JOINTS", "HAS_LOOPS"})
    assert {"solve_with_loops", "tree_points"} <= _kept_globals(with_loops)
    # a copy for closing joints runs only models with them: no step without them (EVERY_KIND)
    for kernel in (kstep.initial_accelerations, kstep._iterate):
        assert "solve_step" in _kept_globals(kernel)
        assert "solve_step" in _kept_globals(kf.specialized(kernel, {"SWEEP_JOINTS"}))
        assert "solve_step" not in _kept_globals(kf.specialized(kernel, {"SWEEP_JOINTS",
                                                                         "HAS_LOOPS"}))


def test_copies_are_shared_named_after_their_features_and_only_where_a_flag_is_read():
    a = kf.specialized(kstep.solve_step, {"SWEEP_FULL", "HAS_BEAMS"})
    assert a is kf.specialized(kstep.solve_step, ["HAS_BEAMS", "SWEEP_FULL"])
    assert a.py_func.__qualname__ == "solve_step__b_F"      # (numba's cache files' names)
    assert kf.specialized(kstep.solve_step) is kstep.solve_step
    assert kf.specialized(kstep._all_finite, {"SWEEP_FULL"}) is kstep._all_finite
    with pytest.raises(ValueError, match="unknown features.*HAS_WINGS"):
        kf.specialized(kstep.solve_step, {"HAS_WINGS"})


def test_fields_no_code_of_a_copy_reads_are_passed_as_none():
    arm = chains.arm()
    sweep = solver.Workspace(solver.kernel_model(arm)[0]).sweep
    for flags, kept in [({"SWEEP_JOINTS"}, {"s", "p", "tree_s", "tree_p"}),
                        ({"SWEEP_REDUCED"}, {"red_v", "red_phi", "red_aq", "red_s", "red_p",
                                             "red_tinv", "red_t"})]:
        trimmed = kf.unread_dropped(sweep, "sweep", frozenset(flags))
        present = {f for f in sweep._fields if getattr(trimmed, f) is not None}
        assert present == kept | {"kind", "u", "known_loads", "joint_dof", "joint_tau_nu",
                                  "joint_nu", "joint_tau"}
    assert kf.unread_dropped(sweep, "sweep", kf.ALL) is sweep


def test_a_model_with_a_kind_its_copy_was_not_compiled_for_is_refused():
    """A beam in a copy compiled without beams ends in the kernel's refusal (the element's
    index), not in a run without the beam."""
    model = _scene_model("flexible_arm")
    km, _ = solver.kernel_model(model)
    mode = solver._mode(km, "riccati", False)
    ws = solver.Workspace(km)
    params = solver.kernel_params(km)
    settings = kloop.Settings(mode=mode, h=1e-3, coef=np.array([0.25, 0.5, 0.5, 0.5]),
                              newton_max=0, newton_tol=1e-10, record_every=1,
                              max_step_error=np.inf, stop_unconverged=False, start=False)
    monitor = kloop.Monitor(np.zeros((km.n_bodies, 3)), np.zeros(len(ws.state.eta)),
                            np.zeros((km.n_bodies, 2)), np.zeros((0, 3)), np.zeros(2))
    with pytest.raises(ValueError, match="does not support body"):
        solver._consistent_start(km, mode, "riccati", None, params, settings, ws.state,
                                 ws.sweep, monitor, 1e-3, features=frozenset({"SWEEP_JOINTS"}))


_SEEN = {}      # a kernel (or its copy) -> (attributes its kept code reads, kernels it calls)
# the names the kernels give each structure (a variable, an argument, or the field it came from)
_NAMES = {"sweep": {"sweep", "sw"}, "loop": {"loop"}, "inputs": {"inputs"}, "rec": {"rec"}}


def _base_name(func_ir, var):
    """The name of what an attribute is read from: the variable's, or for numba's temporaries
    the attribute it was read as (run.sweep.s: 'sweep')."""
    if var.name.startswith("$"):
        definition = ir_utils.guard(ir_utils.get_definition, func_ir, var)
        if isinstance(definition, ir.Expr) and definition.op == "getattr":
            return definition.attr
    return var.name


def _kept_code(kernel):
    found = _SEEN.get(kernel)
    if found is None:
        func_ir = compiler.run_frontend(kernel.py_func)
        analysis.dead_branch_prune(func_ir, [types.int64] * func_ir.arg_count)
        func_ir.blocks = ir_utils.simplify_CFG(func_ir.blocks)
        attrs, calls = set(), []
        for block in func_ir.blocks.values():
            for stmt in block.body:
                if not isinstance(stmt, ir.Assign):
                    continue
                value = stmt.value
                if isinstance(value, ir.Expr) and value.op == "getattr":
                    attrs.add((_base_name(func_ir, value.value), value.attr))
                elif (isinstance(value, (ir.Global, ir.FreeVar))
                      and isinstance(value.value, Dispatcher)):
                    calls.append(value.value)
        found = _SEEN[kernel] = (attrs, calls)
    return found


def _attributes_read(roots, features):
    """Every (structure's name, attribute) the copies of roots for `features` read in the code
    numba keeps, themselves and every kernel they call, to any depth."""
    attrs, todo, done = set(), [kf.specialized(r, features) for r in roots], set()
    while todo:
        kernel = todo.pop()
        if kernel in done:
            continue
        done.add(kernel)
        read, calls = _kept_code(kernel)
        attrs |= read
        todo.extend(calls)          # (a copy's globals already name the callees' copies)
    return attrs


def test_no_kept_code_reads_a_field_its_copy_takes_as_none():
    """A field passed as None where its flags are off (READ_UNDER) is read by no code a copy
    keeps, in the general and energy-momentum loops and the consistent start: checked by name
    on numba's own IR after its dead-branch pruning, for the most features a field is dropped
    under (every other flag on: turning flags off only drops code)."""
    roots = [kloop._skeleton(kstep.GeneralLoop),
             kloop._skeleton(em_step.EnergyMomentumLoop), kstep.initial_accelerations]
    by_flags = {}
    for (structure, field), flags in kf.READ_UNDER.items():
        by_flags.setdefault(frozenset(flags), set()).update(
            (name, field) for name in _NAMES[structure])
    for flags, fields in by_flags.items():
        assert not fields & _attributes_read(roots, kf.ALL - flags), sorted(flags)


def test_a_copy_runs_the_model_as_the_kernels_with_every_feature(monkeypatch):
    """The rigid arm (joints with coordinates, a drive, welded links) on its copy against the
    one copy with every flag on: the same steps, to rounding."""
    runs = {}
    for specialize in (False, True):
        monkeypatch.setattr(kf, "SPECIALIZE", specialize)
        model = _scene_model("arm")
        runs[specialize] = solver.simulate(model, 0.05, 1e-3)
    assert (kloop._skeleton(kstep.GeneralLoop).py_func,
            frozenset({"SWEEP_JOINTS"})) in kf._COPIES
    assert runs[True].joint_coordinates.shape == runs[False].joint_coordinates.shape
    for key in ("rotation", "angular_velocity", "joint_coordinates"):
        assert np.abs(getattr(runs[True], key) - getattr(runs[False], key)).max() < 1e-12, key


def test_with_numba_off_the_kernels_run_as_the_one_copy():
    """NUMBA_DISABLE_JIT=1 (debugging: the kernels as plain Python) with the copies asked for:
    the plain functions run as the copy with every flag on, a general-loop model steps."""
    script = ("from dttmm import chains, simulate\n"
              "from dttmm.kernels import features\n"
              "assert not features.SPECIALIZE\n"
              "print(simulate(chains.arm(drive='motion'), 0.002, 1e-3).n_steps)\n")
    env = dict(os.environ, NUMBA_DISABLE_JIT="1", DTTMM_SPECIALIZE="1")
    done = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.split()[-1] == "2"


def test_the_references_copy_solves_as_its_kernels_with_every_feature():
    """The reference's kernels compiled for what a model uses (newton_euler.py::
    reference_features: equations.py's branches for modal beams, strain rods, elastic hinges,
    closing joints, joints with coordinates and the exact foreshortening of stiffened beams):
    the three-pendulum's copy (beams only) solves its system at a moving state as the kernels
    with every flag on, to rounding; each model gets the flags it uses."""
    from dttmm import BallJoint, EulerBernoulliBeam, build_chain
    from dttmm.mechanisms import slider_crank
    from dttmm.reference.equations import _solve_dynamics
    from dttmm.reference.newton_euler import _Problem
    assert _Problem(_scene_model("arm")).features == {"HAS_JOINTS"}
    assert _Problem(slider_crank()).features == {"HAS_JOINTS", "HAS_LOOPS"}
    for stiffening, option in (("exact", False), (True, True), (True, False)):
        beam = EulerBernoulliBeam(length=1.0, density=2700.0, area=1e-4, bending_stiffness=2.0,
                                  polar_inertia_per_length=0.0045, modes_per_plane=2,
                                  stiffening=stiffening)
        exact = {"HAS_EXACT_STIFFENING"} if stiffening == "exact" or option else set()
        assert _Problem(build_chain([BallJoint(), beam]), option).features == (
            {"HAS_BEAMS"} | exact)
    problem = _Problem(chains.three_pendulum())
    assert problem.features == {"HAS_BEAMS"}
    copy = problem.kernels.solve_dynamics
    assert copy is not _solve_dynamics and copy.py_func.__name__.endswith("__b")
    y = problem.initial_state() + 0.05 * np.sin(np.arange(problem.n_state))    # (moving)
    ours, theirs = copy(*problem._args(y, 0.3)), _solve_dynamics(*problem._args(y, 0.3))
    assert len(ours) == len(theirs) == 18
    for a, b in zip(ours, theirs):
        assert np.abs(np.asarray(a) - np.asarray(b)).max(initial=0.0) < 1e-12

"""Equal links hold their tables once (issue 30, "a million bodies"): where every body's (joint's)
row of a per-body table is the same, the model shows that row for all through a view of stride
0 (model.shared_rows) and the kernels read the one row (run_tables.kernel_params: body_row,
hinge_row).  The runs of such a model equal bit for bit those of the same model with every row
stored, on every loop variant; and the model's memory per body falls accordingly."""
import os
import pickle
import subprocess
import sys
import tracemalloc
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from dttmm import (BallJoint, EulerBernoulliBeam, FixedHinge, RevoluteJoint, RigidBody,
                   build_chain, simulate)
from dttmm.model.chains import binary_tree, rigid_chain
from dttmm.model.model import SHARED_TABLES, is_shared

ROOT = Path(__file__).resolve().parents[1]


def _rod(**extra):
    return RigidBody(mass=1.0, inertia=[1e-3, 1 / 12, 1 / 12], inertia_about="mass_center",
                     to_mass_center=[0.5, 0, 0], to_output=[1.0, 0, 0], **extra)


def _beam():
    return EulerBernoulliBeam(length=1.0, density=2700.0, area=1e-4, bending_stiffness=2.0,
                              polar_inertia_per_length=2700.0 * 1e-4 * 1e-4 / 6,
                              modes_per_plane=2)


def _revolute_chain():
    elements = []
    for _ in range(4):
        elements += [RevoluteJoint(axis=[0, 0, 1]), _rod()]
    return build_chain(elements, gravity=[0, -9.81, 0])


def _welded_beams():
    return build_chain([FixedHinge(), _beam(), FixedHinge(), _beam(), FixedHinge(), _beam()],
                       gravity=[0, -9.81, 0])


# (the model, simulate's options): the fused ball chain, the general loop (full state), the
# energy-momentum loop, the fused tree, joints with coordinates, the welded-chain loop
CASES = {
    "fused ball chain": (lambda: rigid_chain(6), {}),
    "general loop": (lambda: rigid_chain(6), dict(full_state=True)),
    "energy-momentum": (lambda: rigid_chain(6), dict(scheme="energy_momentum")),
    "fused tree": (lambda: binary_tree(3), {}),
    "revolute joints": (_revolute_chain, {}),
    "welded beams": (_welded_beams, {}),
}


def _every_row_stored(model):
    """The same model with its shared tables stored row by row (C order)."""
    return replace(model, **{name: np.array(getattr(model, name), order="C")
                             for name in SHARED_TABLES})


@pytest.mark.parametrize("name", list(CASES))
def test_a_model_of_equal_links_runs_as_the_same_model_with_every_row_stored(name):
    build, options = CASES[name]
    model = build()
    assert is_shared(model.body_params) and is_shared(model.hinge_params)
    full = _every_row_stored(model)
    assert not is_shared(full.body_params) and not is_shared(full.hinge_params)
    a = simulate(model, 0.02, 1e-3, **options)
    b = simulate(full, 0.02, 1e-3, **options)
    for key in ("rotation", "angular_velocity", "force", "moment", "position_output"):
        np.testing.assert_array_equal(getattr(a, key), getattr(b, key), err_msg=key)


def test_a_link_that_differs_keeps_every_row():
    elements = []
    for k in range(4):
        elements += [BallJoint(), _rod() if k != 2 else RigidBody(
            mass=2.0, inertia=[1e-3, 1 / 12, 1 / 12], inertia_about="mass_center",
            to_mass_center=[0.5, 0, 0], to_output=[1.0, 0, 0])]
    model = build_chain(elements)
    assert not is_shared(model.body_params) and is_shared(model.hinge_params)
    assert model.body_params[2, 0] == 2.0 and model.body_params[3, 0] == 1.0


def test_the_tables_of_equal_links_cost_no_memory_per_body():
    """A chain of 20000 equal rods: the model's own memory (numpy's, traced) per body, against
    the 1.1 KB it held with every row stored (body, joint, inertia and beam tables: 0.76 KB of
    it); what is left is the state at t = 0, the tree and the names."""
    n = 20000
    elements = []
    for _ in range(n):
        elements += [BallJoint(), _rod()]
    tracemalloc.start()
    model = build_chain(elements)
    held = tracemalloc.get_traced_memory()[0] / n
    tracemalloc.stop()
    assert all(is_shared(getattr(model, name)) for name in SHARED_TABLES)
    assert held < 450, f"{held:.0f} B per body"


def test_a_run_too_large_to_keep_holds_its_arrays_once():
    """A run of a chain too large to keep on its model (run_plan.KEEP_BYTES) steps the arrays
    it made: numpy's memory traced over the call peaks at 1.70x what the call leaves held (its
    result and checkpoint) for 30000 rods; 2.36x while every run copied its arrays into
    buffers and those into the start's copy, kept or not (10^6 rods peaked at 3.5 GB, the issue
    asking under 2)."""
    model = rigid_chain(30000)
    simulate(rigid_chain(3), 0.002, 1e-3)           # (the kernels loaded first)
    tracemalloc.start()
    result = simulate(model, 0.002, 1e-3)
    held, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert result.n_steps == 2
    assert peak < 2.0 * held, f"peak {peak / 2**20:.0f} MB, held {held / 2**20:.0f} MB"


def test_no_kernel_reads_a_table_past_its_rows():
    """The tables with no or one row (shared rows, the lock and joint-drive tables, the beams'
    without beams) are read within their rows on every loop variant: the cases above and a
    ball-joint tree on the full-state sweep, and the high-order scheme's stages on the fused
    chain, two steps each with numba's compilation off (pure Python: numpy refuses an index past
    the end, where compiled code would read past it).  The fused loops' state has no rows of
    joint offsets, coordinates or mass-centre velocities (run_tables.Workspace): read here too."""
    script = (
        "import sys; sys.path.insert(0, 'tests')\n"
        "from test_shared_rows import CASES\n"
        "from dttmm import simulate\n"
        "from dttmm.model.chains import binary_tree, rigid_chain\n"
        "cases = list(CASES.values()) + [(lambda: binary_tree(2), dict(full_state=True)),\n"
        "                                (lambda: rigid_chain(4), dict(scheme='dop853'))]\n"
        "for build, options in cases:\n"
        "    simulate(build(), 0.002, 1e-3, **options)\n")
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    done = subprocess.run([sys.executable, "-c", script], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]


def test_a_pickled_model_of_equal_links_comes_back_shared_and_runs_the_same():
    """A pickle holds every row (numpy writes a view's values); the model read back shares its
    equal rows again and runs bit for bit as the original (a Dask worker's copy)."""
    model = rigid_chain(5)
    copy = pickle.loads(pickle.dumps(model))
    assert all(is_shared(getattr(copy, name)) == is_shared(getattr(model, name))
               for name in SHARED_TABLES)
    assert is_shared(copy.hinge_params)
    a, b = simulate(model, 0.01, 1e-3), simulate(copy, 0.01, 1e-3)
    np.testing.assert_array_equal(a.rotation, b.rotation)
    np.testing.assert_array_equal(a.force, b.force)

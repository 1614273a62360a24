"""The flat model and the flat run data (issue 66, item 2; kernels/schema.py): a model's tables,
the closing joints' tables and scratch, the state, the sweep's, the general loop's and the fused
loops' scratch, a chunk's inputs and record and the error monitor, each in two buffers whose
offsets and sizes come from one schema, read by the kernels through accessors generated from it
(kernels/model_tables.py, kernels/loop_tables.py, ...)."""
import numpy as np
import pytest
from numba import njit

from dttmm import (BallJoint, EulerBernoulliBeam, FixedHinge, RevoluteJoint, StrainRod,
                   build_chain)
from dttmm.solving import run_tables
from dttmm.model.chains import arm, unit_link
from dttmm.kernels import loop_tables, model_tables, schema, state_tables, sweep_tables
from dttmm.kernels.schema import LOOP_LAYOUT, MODEL, SIZES, pack, unpack
from dttmm.model.mechanisms import n_four_bar


@pytest.mark.parametrize("layout", schema.LAYOUTS, ids=lambda layout: layout.generated.name)
def test_the_accessors_are_generated_from_the_schema(layout):
    """kernels/model_tables.py and kernels/loop_tables.py are what the schema generates (after an
    edit of the schema: schema.write())."""
    assert layout.generated.read_text() == layout.generated_source(), \
        f'kernels/{layout.generated.name} is stale: python -c "from dttmm.kernels import ' \
        'schema; schema.write()"'


def _models():
    beam = EulerBernoulliBeam(length=1.0, bending_stiffness=175.0, density=7850.0, area=1e-4,
                              polar_inertia_per_length=1.3e-4, modes_per_plane=3,
                              torsion_modes=1, torsional_stiffness=100.0,
                              axial_stiffness=2e7, axial_modes=1)
    rod = StrainRod(length=0.3, bending_stiffness=50.0, mass_per_length=1.0,
                    polar_inertia_per_length=1e-4)
    return {
        "flexible arm": arm(drive="pd", flexible=True),
        "four-bar": n_four_bar(2),
        "beam welded to a body": build_chain([BallJoint(), beam, FixedHinge(), unit_link()]),
        "strain rod behind revolute joints": build_chain(
            [RevoluteJoint(axis=[0, 0, 1.0]), unit_link(), RevoluteJoint(axis=[0, 1.0, 0]), rod]),
    }


@pytest.mark.parametrize("name", list(_models()))
def test_a_model_packed_reads_back_its_own_tables(name):
    """Every table of a packed model reads back, by name, equal to the table it was packed from
    (run_tables' own, built apart: beam_tables, rod_tables, joint_drives), shape and values, and
    the sizes are those of the model."""
    km = run_tables.kernel_model(_models()[name])[0]
    flat = run_tables.kernel_params(km)
    tables = unpack(flat)
    beams = dict(zip(["body_kind", "beam_params", "beam_moments", "mode_offset", "beam_ends",
                      "beam_factors"], run_tables.beam_tables(km)))
    rods = dict(zip(["rod_row", "rod_steps", "rod_xi0", "rod_phi", "rod_weights",
                     "rod_stiffness", "rod_mu_damping", "rod_section"],
                    run_tables.rod_tables(km)))
    expected = dict(beams, **rods, hinge_kind=km.hinge_kind, parent=km.parent,
                    gravity=km.gravity, locked=km.ground_locked,
                    joint_drive=run_tables.joint_drives(km), tip_pinned=int(km.tip_pinned))
    for key, value in expected.items():
        np.testing.assert_array_equal(tables[key], value, err_msg=key)
        assert np.shape(tables[key]) == np.shape(value), key
    n = km.n_bodies
    assert flat.size[[s for s, _ in SIZES].index("bodies")] == n
    for k in range(n):      # each body's row of the shared tables is its own parameters
        np.testing.assert_array_equal(tables["body_params"][tables["body_row"][k]],
                                      km.body_params[k])
        np.testing.assert_array_equal(tables["hinge_params"][tables["hinge_row"][k]],
                                      km.hinge_params[k])
    assert flat.real.dtype == np.float64 and flat.int.dtype == np.int64
    assert flat.real.size == sum(tables[f.name].size for f in MODEL if f.buffer == schema.REAL)


def _reader(accessor):
    @njit
    def read(m):
        return accessor(m)
    return read


def _reads_back(layout, flat, accessors):
    """Every table of a flat structure read by its compiled accessor equals the table Python
    reads by name and unpack's, of the same shape, a view of the buffers where it has entries
    (a table without axes reads as its one value)."""
    tables = layout.unpack(flat)
    for field in layout.fields:
        got = _reader(getattr(accessors, field.name))(flat)
        np.testing.assert_array_equal(got, tables[field.name], err_msg=field.name)
        np.testing.assert_array_equal(getattr(flat, field.name), tables[field.name],
                                      err_msg=field.name)
        assert np.shape(got) == np.shape(getattr(flat, field.name)), field.name
        if np.size(got) and np.ndim(got):
            buffer = flat.real if field.buffer == schema.REAL else flat.int
            assert np.shares_memory(got, buffer), field.name


def test_each_compiled_accessor_reads_its_table():
    """The accessors the kernels call (compiled) return each table's view of the buffers: the
    same shape and values as Python's unpack, and a view (no copy) of a table with entries."""
    km = run_tables.kernel_model(arm(drive="pd", flexible=True))[0]
    flat = run_tables.kernel_params(km)
    tables = unpack(flat)
    for field in MODEL:
        got = _reader(getattr(model_tables, field.name))(flat)
        want = tables[field.name]
        np.testing.assert_array_equal(got, want, err_msg=field.name)
        assert np.shape(got) == np.shape(want), field.name
        if np.size(want) and np.ndim(want):
            buffer = flat.real if field.buffer == schema.REAL else flat.int
            assert np.shares_memory(got, buffer), field.name


def test_pack_refuses_tables_that_disagree_on_a_size():
    """Two tables that give one size two values, a table of the wrong rank or width, and a
    missing or unknown table are refused, naming the table."""
    km = run_tables.kernel_model(arm())[0]
    good = unpack(run_tables.kernel_params(km))
    with pytest.raises(ValueError, match="parent's axis bodies"):
        pack(**dict(good, parent=np.zeros(km.n_bodies + 1, dtype=np.int64)))
    with pytest.raises(ValueError, match="body_params has shape"):
        pack(**dict(good, body_params=np.zeros((km.n_bodies, 3))))
    with pytest.raises(TypeError, match="missing tables \\['gravity'\\]"):
        pack(**{k: v for k, v in good.items() if k != "gravity"})
    with pytest.raises(TypeError, match="unknown tables \\['mass'\\]"):
        pack(**dict(good, mass=np.zeros(3)))


def test_the_loops_tables_read_back_by_name_in_python_and_in_kernels():
    """A four-bar's closing joints (run_tables.loop_tables) packed flat: every table reads back
    from the accessors the kernels call as Python reads it by name (loops.kind), a view of the
    buffers; the sizes are the four-bar's (its rows, closing joints and bodies, counted apart);
    a run's copy writes its own buffers; a table the layout does not name is no attribute."""
    model = n_four_bar(2)
    km = run_tables.kernel_model(model)[0]
    loops = run_tables.loop_tables(km)
    _reads_back(LOOP_LAYOUT, loops, loop_tables)
    # two revolute joints close it, 5 rows each (3 gaps, 2 dots)
    assert len(loops.kind) == 10 and LOOP_LAYOUT.size(loops, "rows") == 10
    assert LOOP_LAYOUT.size(loops, "closings") == 2
    assert LOOP_LAYOUT.size(loops, "bodies") == km.n_bodies
    other = run_tables.loop_tables(km)
    loops.stats[:] = 7.0
    assert not np.shares_memory(loops.real, other.real) and (other.stats == 0.0).all()
    with pytest.raises(AttributeError):
        loops.mass


@pytest.mark.parametrize("fused", [False, True])
def test_the_state_and_the_sweep_read_back_by_name_in_python_and_in_kernels(fused):
    """A run's state and the assembly's scratch (run_tables.Workspace) packed flat: every
    table reads back from the kernels' accessors as Python reads it by name, a view of the
    buffers, with the model's initial rotations and rates in it; where a fused loop runs, the
    per-body tables only the general loop reads have no rows."""
    model = arm(drive="pd", flexible=True) if not fused else build_chain(
        [BallJoint(), unit_link(), BallJoint(), unit_link()])
    km = run_tables.kernel_model(model)[0]
    ws = run_tables.Workspace(km, fused=fused)
    n = km.n_bodies
    _reads_back(schema.STATE_LAYOUT, ws.state, state_tables)
    _reads_back(schema.SWEEP_LAYOUT, ws.sweep, sweep_tables)
    np.testing.assert_array_equal(ws.state.rot, km.initial_rotation)
    np.testing.assert_array_equal(ws.state.omega, km.initial_angular_velocity)
    assert ws.state.z.shape == (2 * n + 1, 12) and ws.sweep.red_aq.shape == (n + 1, 6)
    assert ws.state.jq.shape[0] == ws.sweep.u.shape[0] // 2 == (0 if fused else n)


def test_the_general_loops_scratch_reads_back_by_name_in_python_and_in_kernels():
    """The general loop's own scratch (kernels/stepping/step.py::general_loop) packed flat:
    every table reads back from the kernels' accessors as Python reads it by name; the ground's
    dw'/dphi starts at c1 I, the paper's scheme's flag and histories are the ones given, and the
    compiled JointForces' addresses are kept as given."""
    from dttmm.kernels import general_tables
    from dttmm.kernels.stepping import step as kstep
    km = run_tables.kernel_model(arm(drive="pd", flexible=True))[0]
    n, n_eta, h = km.n_bodies, int(km.n_modes.sum()), 1e-3
    coef = np.array([0.25, 0.5, 0.5, 0.5])
    st = np.arange(3.0 * (n + 1)).reshape(n + 1, 3)
    c = np.arange(3.0 * n).reshape(n, 3)
    loop = kstep.general_loop(n, n_eta, h, coef, (True, st, 2 * st, 3 * st, c, 2 * c, 3 * c),
                              run_tables.loop_tables(km), np.array([7, 9], dtype=np.int64))
    scratch = loop.scratch
    _reads_back(schema.GENERAL_LAYOUT, scratch, general_tables)
    c1 = (1.0 - 0.5) / ((1.0 - 0.5) * 0.25 * h * h)        # docs/solver.md, the step's c1
    np.testing.assert_allclose(scratch.ground_dwd, c1 * np.eye(3), rtol=1e-15)
    assert scratch.independent == 1 and scratch.eta_g.shape == (n_eta,)
    np.testing.assert_array_equal(scratch.st_a, 2 * st)
    np.testing.assert_array_equal(scratch.c_p, 3 * c)
    np.testing.assert_array_equal(scratch.forces, [7, 9])


def test_a_chunks_inputs_record_and_monitor_read_back_by_name_in_python_and_in_kernels():
    """A chunk's inputs (packed from its tables, as Stepping.inputs_for packs them), its record
    and the error monitor (made by size, Layout.zeros) flat: every table reads back from the
    kernels' accessors as Python reads it by name, a view of the buffers, of the shape its sizes
    give; the paper's point velocities, the mass centres' and the closing joints' wrenches have
    slots only where recorded."""
    from dttmm.elements.kinds import MAX_COORDINATES
    from dttmm.kernels import input_tables, monitor_tables, record_tables
    from dttmm.solving.consistent_start import _record
    m, n, rows = 3, 4, 5
    values = {f.name: np.arange(float(np.prod(shape))).reshape(shape) + 1000.0 * i
              for i, (f, shape) in enumerate(
                  (f, tuple({"steps": m, "steps+1": m + 1, "bodies": n, "rows": rows}.get(a, a)
                            for a in f.shape)) for f in schema.INPUTS)}
    inputs = schema.INPUT_LAYOUT.pack(**values)
    assert inputs.steps == m and inputs.g_rot.shape == (m + 1, 3, 3)
    record = _record(6, n, 7, v_st=True, n_closures=2)
    monitor = schema.MONITOR_LAYOUT.zeros(bodies=n, modes=7, coordinate_bodies=n,
                                          elastic_bodies=0)
    _reads_back(schema.INPUT_LAYOUT, inputs, input_tables)
    _reads_back(schema.RECORD_LAYOUT, record, record_tables)
    _reads_back(schema.MONITOR_LAYOUT, monitor, monitor_tables)
    for name, value in values.items():
        np.testing.assert_array_equal(getattr(inputs, name), value, err_msg=name)
    assert record.rot.shape == (6, n, 3, 3) and record.z.shape == (6, 2 * n + 1, 12)
    assert record.v_st.shape == (6, n + 1, 3) and record.v_c.shape == (1, n, 3)
    assert record.closure_wrench.shape == (6, 2, 10) and record.eta.shape == (6, 7)
    assert monitor.jqp.shape == (n, MAX_COORDINATES) and monitor.defl_pseudo.shape == (0, 3)
    assert monitor.error.shape == (2,) and not monitor.error.any()


def test_the_fused_loops_scratch_reads_back_by_name_in_python_and_in_kernels():
    """The fused loops' own scratch (FUSED for ball chains and trees, WELD, MOMENTUM and
    RUNGE_KUTTA), made by their constructors: every table reads back from the kernels'
    accessors as Python reads it by name (the buffers filled with distinct values first), a
    chain has no rows of the tree's tables, a tree keeps its parents, the welded loop its
    stations' guess from z, DOP853's scratch scipy's tableau."""
    from dttmm.kernels import fused_tables, momentum_tables, runge_kutta_tables, weld_tables
    from dttmm.kernels.stepping import ball_chain, em_step, runge_kutta, tree, weld_chain
    mode_off = np.array([0, 4, 4, 10])              # a beam of 4, a body, a beam of 6 modes
    coef = np.array([0.25, 0.5, 0.0, 0.0])
    chain = ball_chain.fused_loop(3, mode_off, 1e-3, coef)
    ball_tree = tree.fused_tree_loop(3, [-1, 0, 0], mode_off, 1e-3, coef)
    z = np.arange(7 * 12.0).reshape(7, 12)
    welded = weld_chain.weld_loop(3, mode_off, 1e-3, coef, z)
    tableau = runge_kutta.dop853_tables()
    rk = runge_kutta.runge_kutta_scratch(3, 10, tableau)
    momentum = em_step.energy_momentum_loop(3)
    assert type(chain) is schema.FlatFused and type(ball_tree) is schema.FlatFusedTree
    assert chain.maps.shape == (0, 6, 7) and ball_tree.maps.shape == (3, 6, 7)
    np.testing.assert_array_equal(ball_tree.parent, [-1, 0, 0])
    assert chain.per_mode.shape == (5, 10) and chain.beam_work.shape[1] == 12 + 6
    np.testing.assert_array_equal(welded.stations[:3], z[1:6:2])
    np.testing.assert_array_equal(welded.stations[3], z[6])
    np.testing.assert_array_equal(chain.coefficients, welded.coefficients)
    for table, want in zip(("tableau_a", "tableau_b", "tableau_c", "error_e3", "error_e5",
                            "dense_d"), tableau):
        np.testing.assert_array_equal(getattr(rk, table), want, err_msg=table)
    assert rk.y.shape == (6 * 3 + 2 * 10,) and momentum.z_star.shape == (7, 12)
    for layout, flat, accessors in ((schema.FUSED_LAYOUT, chain, fused_tables),
                                    (schema.FUSED_LAYOUT, ball_tree, fused_tables),
                                    (schema.WELD_LAYOUT, welded, weld_tables),
                                    (schema.RUNGE_KUTTA_LAYOUT, rk, runge_kutta_tables),
                                    (schema.MOMENTUM_LAYOUT, momentum, momentum_tables)):
        flat.real[:] = np.arange(len(flat.real)) + 0.5
        flat.int[:] = np.arange(len(flat.int))
        _reads_back(layout, flat, accessors)
    # the consistent start runs on the loop itself: its coefficients set, the step's returned
    km = run_tables.kernel_model(build_chain([BallJoint(), unit_link()] * 3))[0]
    ws = run_tables.Workspace(km, fused=True)
    rigid = ball_chain.fused_loop(3, km.mode_offsets, 1e-3, coef)
    step = rigid.coefficients.copy()
    np.testing.assert_array_equal(ball_chain.start_loop(rigid, ws.state, ws.sweep), step)
    np.testing.assert_array_equal(rigid.coefficients, [1.0, 0.0, 0.0, 0.0])
    np.testing.assert_array_equal(rigid.per_body[1], km.initial_angular_velocity)

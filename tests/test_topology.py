"""The system builder (dttmm.System): trees of bodies joined at named attachment points, chains
as a special case, and the element kinds declared once (elements/kinds.py)."""
import dataclasses

import numpy as np
import pytest

import dttmm
from dttmm import (BallJoint, ElasticHinge, FixedHinge, RigidBody, System, build_chain,
                   simulate)
from dttmm.model.chains import three_pendulum, unit_link
from dttmm.elements import BODY_KINDS, JOINT_KINDS, kinds


def _five_link_tree():
    """The issue's tree: links 2 and 4 on link 1's output, 3 on 2's, 5 on 4's."""
    turned = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])   # +90 deg about y
    system = System(gravity=[0.0, -9.81, 0.0])
    links = {}
    links[1] = system.add(unit_link(name="link1"), BallJoint())
    links[2] = system.add(unit_link(name="link2"), BallJoint(), parent=links[1])
    links[3] = system.add(unit_link(name="link3", angular_velocity=[0, 0.1, 0]), BallJoint(),
                          parent="link2")
    links[4] = system.add(unit_link(name="link4", rotation=turned), BallJoint(), parent="link1")
    system.add(unit_link(name="link5", rotation=turned, angular_velocity=[0.2, 0, 0]),
               BallJoint(), parent=links[4])
    return system


def test_a_chain_through_the_builder_is_the_chain():
    """The three-pendulum built by build_chain and by System.add: the same model, the same run
    to 1e-13."""
    chain = three_pendulum()
    system = System()
    parent = None
    elements = _three_pendulum_elements()
    for hinge, body in zip(elements[0::2], elements[1::2]):
        parent = system.add(body, hinge, parent=parent)
    built = system.build()
    assert built.is_chain and np.array_equal(built.parent, np.arange(3) - 1)
    for name in ("body_params", "hinge_kind", "hinge_params", "beam_params", "initial_rotation",
                 "initial_angular_velocity", "body_kind"):
        np.testing.assert_array_equal(getattr(built, name), getattr(chain, name))
    a = simulate(chain, 0.05, 1e-4)
    b = simulate(built, 0.05, 1e-4)
    assert np.abs(a.position_output - b.position_output).max() <= 1e-13
    assert np.abs(a.force - b.force).max() <= 1e-13


def _three_pendulum_elements():
    from dttmm import EulerBernoulliBeam
    side = 0.02
    area = side * side
    beam = EulerBernoulliBeam(length=1.0, density=3300.0, area=area,
                              bending_stiffness=1.0 * 2.5e10 * side ** 4 / 12.0,
                              polar_inertia_per_length=3300.0 * area * side * side / 6.0,
                              modes_per_plane=2, stiffening=False, name="beam4")
    return [BallJoint(name="joint1"), unit_link(name="body2"), BallJoint(name="joint3"), beam,
            BallJoint(name="joint5"), unit_link(name="body6", angular_velocity=[0.0, 0.1, 0.0])]


def test_a_tree_freezes_with_its_topology():
    model = _five_link_tree().build()
    assert model.body_names == ("link1", "link2", "link3", "link4", "link5")
    assert list(model.parent) == [-1, 0, 1, 0, 3]
    assert not model.is_chain
    np.testing.assert_allclose(model.attachment_point[[1, 3]], [[1, 0, 0], [1, 0, 0]])
    # links 4 and 5 start turned by +90 deg about y: their x axes point along -z
    np.testing.assert_allclose(model.initial_rotation[3] @ [1, 0, 0], [0, 0, -1], atol=1e-15)
    # what trees do not run yet is refused by name, before the run
    with pytest.raises(ValueError, match="direct.*tree.*link4.*riccati"):
        simulate(model, 0.01, 1e-3, method="direct")


def test_parents_may_come_later_and_are_placed_first():
    system = System()
    tip = unit_link(name="tip")
    system.add(tip, BallJoint(), parent="root")
    system.add(unit_link(name="root"), BallJoint())
    model = system.build()
    assert model.body_names == ("root", "tip") and model.is_chain


def test_named_attachment_points():
    system = System()
    hub = system.add(RigidBody(mass=2.0, inertia=[1, 1, 1], inertia_about="mass_center",
                               to_output=[1, 0, 0], points={"side": [0, 0, 0.5]}, name="hub"),
                     BallJoint())
    system.add(unit_link(name="arm"), BallJoint(), parent=hub, at="side")
    model = system.build()
    assert list(model.attachment) == [0, 1] and not model.is_chain
    np.testing.assert_allclose(model.attachment_point[1], [0, 0, 0.5])
    res = simulate(model, 0.01, 1e-3)           # the arm's input point is the hub's "side"
    np.testing.assert_allclose(res.position_input[0, 1], [0, 0, 0.5], rtol=0, atol=1e-15)
    assert res.position_input.shape == (11, 2, 3)


@pytest.mark.parametrize("build, words", [
    (lambda s: s.add(unit_link(name="a"), BallJoint(), parent="nowhere"),
     "'a'.*parent 'nowhere' is not in the system"),
    (lambda s: s.add(unit_link(name="a"), BallJoint(), parent=unit_link(name="stranger")),
     "'a'.*parent RigidBody 'stranger' is not in the system"),
    (lambda s: (s.add(unit_link(name="a"), BallJoint(), parent="b"),
                s.add(unit_link(name="b"), BallJoint(), parent="a")), "cycle.*'a'.*'b'"),
    (lambda s: (s.add(unit_link(name="a"), BallJoint()),
                s.add(unit_link(name="b"), BallJoint(), parent="a", at="elbow")),
     "'b'.*at='elbow'.*'a' has no attachment point 'elbow'.*output"),
    (lambda s: s.add(unit_link(name="a"), BallJoint(), at="elbow"), "'a'.*ground"),
    (lambda s: (s.add(unit_link(name="a"), BallJoint()), s.add(unit_link(name="a"), BallJoint())),
     "two bodies are named 'a'"),
    (lambda s: [s.add(b, BallJoint()) for b in [unit_link(name="a")] * 2], "'a'.*added twice"),
    (lambda s: s.add(BallJoint(), unit_link()), "not a body"),
    (lambda s: s.add(unit_link(name="a"), unit_link()), "'a'.*joint must be one of"),
    (lambda s: None, "no bodies"),
])
def test_bad_topology_names_the_body(build, words):
    system = System()
    build(system)
    with pytest.raises(ValueError, match=words):
        system.build()


def test_bad_attachment_points_name_the_body_and_argument():
    with pytest.raises(ValueError, match="'hub'.*points.*'output'"):
        RigidBody(mass=1, inertia=1, inertia_about="input", points={"output": [0, 0, 0]},
                  name="hub").validated()
    with pytest.raises(ValueError, match=r"'hub'.*points\['p'\].*NaN"):
        RigidBody(mass=1, inertia=1, inertia_about="input", points={"p": [0, np.nan, 0]},
                  name="hub").validated()
    system = System()
    system.add(unit_link(name="a"), BallJoint())
    system.add(unit_link(name="b"), BallJoint(), parent="a")
    system.add(unit_link(name="c"), BallJoint(), parent="a")
    with pytest.raises(ValueError, match="tip='ball'.*tree"):
        system.build(tip="ball")


def test_every_kind_is_declared_once_and_exported():
    codes = [k.code for k in BODY_KINDS], [k.code for k in JOINT_KINDS]
    for c in codes:
        assert len(set(c)) == len(c)
    for kind in BODY_KINDS + JOINT_KINDS:
        assert getattr(dttmm, kind.name) is kind.cls
        assert set(kind.schemes) <= set(kinds.SCHEMES) and kind.doc and kind.what
    assert kinds.body_kind_of(unit_link()).name == "RigidBody"
    assert kinds.joint_kind_of(ElasticHinge(1.0, 1.0)).name == "ElasticHinge"
    assert kinds.joint_kind_of(unit_link()) is None


def test_an_undeclared_kind_is_refused_not_run_as_another():
    """A kind code no declaration knows is refused before the run, and the kernels' own
    dispatch refuses it too (they never run it as a rigid body or a weld)."""
    model = build_chain([BallJoint(), unit_link(), FixedHinge(), unit_link()])
    odd_body = dataclasses.replace(model, body_kind=np.array([0, 7]))
    with pytest.raises(ValueError, match="body 'body1' has kind code 7"):
        simulate(odd_body, 0.01, 1e-3)
    odd_hinge = dataclasses.replace(model, hinge_kind=np.array([0, 9]))
    with pytest.raises(ValueError, match="hinge 'FixedHinge1' has kind code 9"):
        simulate(odd_hinge, 0.01, 1e-3)
    # the kernels, bypassing the check: the consistent start reports the element, alone
    # (statics, linear models) and as one pass of the general loop's skeleton (a run's)
    from dttmm.kernels.assembly import solve as ksolve
    from dttmm.kernels.schema import MONITOR_LAYOUT
    from dttmm.kernels.stepping.loop import Settings
    from dttmm.solving.run_tables import Workspace, kernel_params
    from dttmm.solving.consistent_start import _consistent_start
    for odd, element in ((odd_body, "body 'body1' \\(kind 7\\)"),
                         (odd_hinge, "hinge 'FixedHinge1' \\(kind 9\\)")):
        ws = Workspace(odd)
        settings = Settings(ksolve.RICCATI_FULL, 1e-3, np.array([0.25, 0.5, 0.5, 0.5]), 0, 1e-12,
                            1, np.inf, False, False)
        monitor = MONITOR_LAYOUT.zeros(bodies=2, modes=0, coordinate_bodies=0, elastic_bodies=0)
        for in_skeleton in (False, True):
            with pytest.raises(ValueError,
                               match=f"consistent start does not support {element}"):
                _consistent_start(odd, ksolve.RICCATI_FULL, "riccati", None, kernel_params(odd),
                                  settings, ws.state, ws.sweep, monitor, 1e-3,
                                  in_skeleton=in_skeleton)


def test_every_body_kind_declares_what_the_package_asks_of_it():
    """Each body kind declares, in elements/kinds.py, its scene type, whether it has coordinates
    of its own (flexible: then its class's names of their initial values and rates), its doc and
    its words; the scene files read and write every declared kind from that (issue 66, item 4)."""
    from dttmm.interfaces import scene
    assert kinds.FLEXIBLE == tuple(k.code for k in BODY_KINDS if k.flexible)
    assert len({k.scene for k in BODY_KINDS}) == len(BODY_KINDS)
    for kind in BODY_KINDS:
        assert kind.scene and kind.doc and kind.what, kind
        assert kinds.declared_body_kind(kind.code) is kind
        if kind.flexible:
            fields = {f.name for f in dataclasses.fields(kind.cls)}
            assert len(kind.arguments) == 2 and set(kind.arguments) <= fields, kind
        else:
            assert kind.arguments == (), kind
        assert scene._BODY_KINDS[kind.scene][0] is kind.cls
        assert kind.code in scene._BODY_TABLES


def test_an_undeclared_body_kind_is_refused_by_the_python_layer():
    """A body kind code no declaration names, in a model's tables, is refused with a ValueError
    naming the body and the code wherever the Python layer dispatches on the kinds (never run as
    a rigid body); a declared kind a place does not implement is refused naming its kind."""
    from dttmm.interfaces.scene import scene_of
    from dttmm.model.loop_kinematics import start_state
    from dttmm.reference import simulate_reference
    from dttmm.solving.statics import _positions
    model = build_chain([BallJoint(), unit_link(), FixedHinge(), unit_link()])
    odd = dataclasses.replace(model, body_kind=np.array([0, 7]))
    named = "body 'body1' has kind code 7, which no body kind declares"
    for call, where in ((lambda: simulate_reference(odd, 0.01), "simulate_reference: "),
                        (lambda: scene_of(odd), "save_scene: "),
                        (lambda: start_state(odd), ""),
                        (lambda: _positions(odd), "")):
        with pytest.raises(ValueError, match=where + named):
            call()
    error = kinds.unimplemented_body_kind(kinds.ROD, "body 'r'", "the paper's scheme")
    assert "body 'r' is a strain rod (StrainRod), which the paper's scheme does not " \
           "implement" in str(error)


def test_the_reference_kernels_refuse_an_undeclared_body_kind():
    """Past the Python layer's check, the reference's kernels refuse the code too
    (elements/kinds.py, UNDECLARED_BODY_KIND), rather than run it as a rigid body."""
    from dttmm.reference.problem import _Problem
    prob = _Problem(build_chain([BallJoint(), unit_link(), FixedHinge(), unit_link()]))
    y = prob.initial_state()
    prob.rhs(0.0, y)                # (runs as it is)
    prob.body_kind[1] = 7
    with pytest.raises(ValueError, match=kinds.UNDECLARED_BODY_KIND.replace("(", r"\(")
                       .replace(")", r"\)")):
        prob.rhs(0.0, y)


def test_a_start_pass_that_ends_without_detail_never_reads_as_done():
    """A start pass's loop status maps to the start's code (consistent_start._start_status): done
    only on OK; a status that carries no element (NOT_FINITE, UNCONVERGED, ...) is the
    not-finite start, never 0, whichever loop ran the pass."""
    from dttmm.kernels.stepping.loop import (NOT_FINITE, OK, SINGULAR, UNCONVERGED,
                                             UNSUPPORTED)
    from dttmm.solving.consistent_start import _NOT_FINITE_START, _start_status

    def info(status, detail):
        return np.array([status, 0, detail, 0, 0], dtype=np.int64)
    assert _start_status(info(OK, 0)) == 0
    assert _start_status(info(SINGULAR, 3)) == 3
    assert _start_status(info(UNSUPPORTED, 4)) == -4
    for status in (NOT_FINITE, UNCONVERGED):
        assert _start_status(info(status, 0)) == _NOT_FINITE_START


def test_schemes_are_checked_against_the_declarations():
    elastic = build_chain([BallJoint(), unit_link(),
                           ElasticHinge(1e4, 1e3, name="spring"), unit_link()])
    for scheme, covered in (("energy_momentum", "BallJoint, FixedHinge, FreeJoint"),
                            ("paper", "BallJoint, FixedHinge")):
        with pytest.raises(ValueError, match=f"hinge 'spring' is elastic.*covers {covered} "
                                             f"only"):
            simulate(elastic, 0.01, 1e-3, scheme=scheme)
    beam = three_pendulum()
    with pytest.raises(ValueError, match="body 'beam4' is a beam.*covers RigidBody only"):
        simulate(beam, 0.01, 1e-3, scheme="energy_momentum")


def test_equal_elements_are_checked_once_and_keep_their_names_and_messages(monkeypatch):
    """The build checks each distinct set of parameters once (a million equal links: one
    check, issue 30): five equal links, their names aside, are checked once and pack to the
    rows each would on its own; a bad one among them is named by its own index; a matrix
    given as nested lists (a key the shallow one cannot hash) is shared too."""
    rod = dict(mass=1.0, inertia=[[1e-4, 0, 0], [0, 1 / 12, 0], [0, 0, 1 / 12]],
               inertia_about="mass_center", to_mass_center=[0.5, 0, 0], to_output=[1.0, 0, 0])
    links = [RigidBody(**rod, name=f"l{k}") for k in range(5)]
    calls = []
    original = RigidBody.validated
    monkeypatch.setattr(RigidBody, "validated",
                        lambda self, index=None: calls.append(index) or original(self, index))
    model = build_chain([x for link in links for x in (BallJoint(), link)])
    assert calls == [0]
    assert model.body_names == ("l0", "l1", "l2", "l3", "l4")
    from dttmm.elements.rigid_body import pack_body
    for k, link in enumerate(links):
        assert np.array_equal(model.body_params[k], pack_body(original(link, k)))
    bad = RigidBody(**dict(rod, mass=-1.0), name="bad")
    with pytest.raises(ValueError, match=r"RigidBody 'bad' \(body 3\): mass"):
        build_chain([x for link in links[:3] + [bad] + links[3:] for x in (BallJoint(), link)])

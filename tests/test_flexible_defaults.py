"""Flexible links right by default behind joints and in loops (issue 65, item 3).

A beam's default mode count was estimated as a cantilever's, whatever its ends: behind a
revolute joint the root turns freely in the plane of motion (pinned there), and two polynomial
modes miss the pinned beam's first flexible frequency by 11%; in a closed loop the stiffening
was turned off for every beam without stretch modes, also where the loop's ends move (a
four-bar's coupler: 1.8x the deflection).  Each case here is checked against a converged fine
mesh of the project's own beams (8 elements a link: 0.1-0.2% of the peak from 16 elements,
measured), never against the same model with the same defaults.
"""
import numpy as np
import pytest

import dttmm
from dttmm import (EulerBernoulliBeam, FixedHinge, JointMotion, RevoluteJoint, RigidBody, StrainRod,
                   System, assemble, simulate)
from dttmm.elements.beam import (CLAMPED, CLAMPED_LOADED, EXACT, MODES, STIFFENING,
                                 _unit_beam_with_ends)
from dttmm.elements.strain_rod import ROD_MODES
from dttmm.model.rod_motion import rod_centre_line
from dttmm.results.result import beam_midpoint_deflection
from helpers import rot_z

Z = [0, 0, 1.0]
STEEL = dict(E=210e9, rho=7850.0)


def steel_rod(length, d, name, **kw):
    area, second = np.pi * d ** 2 / 4, np.pi * d ** 4 / 64
    return EulerBernoulliBeam(length=length, bending_stiffness=STEEL["E"] * second,
                              density=STEEL["rho"], area=area,
                              polar_inertia_per_length=STEEL["rho"] * 2 * second, name=name, **kw)


def steel_strain_rod(length, d, name):
    area, second = np.pi * d ** 2 / 4, np.pi * d ** 4 / 64
    return StrainRod(length=length, bending_stiffness=STEEL["E"] * second,
                     mass_per_length=STEEL["rho"] * area,
                     polar_inertia_per_length=STEEL["rho"] * 2 * second, name=name)


def double_pendulum(elements=1, kind=steel_rod):
    """Two steel links (1 m, 10 mm round; modal beams, or kind=steel_strain_rod) on revolute
    joints about z, a 1 kg tip mass welded to the second, released from horizontal under
    gravity along -y; `elements` elements a link."""
    system = System(gravity=[0, -9.81, 0])
    parent = None
    for link in range(2):
        for e in range(elements):
            name = f"b{link}e{e}"
            system.add(kind(1.0 / elements, 0.010, name),
                       RevoluteJoint(axis=Z) if e == 0 else FixedHinge(), parent=parent)
            parent = name
    system.add(RigidBody(mass=1.0, inertia=[1e-6] * 3, inertia_about="mass_center",
                         name="tip"), FixedHinge(), parent=parent)
    return system.build()


def crank_rocker(elements=1):
    """Ground 1.5 m, a rigid crank 0.5 m (0.5 kg) turned at 1 rev/s about z, a 1.5 m steel
    coupler (8 mm round, `elements` beams), a rigid rocker 1.0 m (1 kg) hanging from the
    coupler's end and closed to the ground at (1.5, 0) by a revolute joint; gravity along -y."""
    def bar(name, length, mass, angle):
        return RigidBody(mass=mass, inertia=[1e-6, mass * length ** 2 / 12,
                                             mass * length ** 2 / 12],
                         inertia_about="mass_center", to_mass_center=[length / 2, 0, 0],
                         to_output=[length, 0, 0], rotation=rot_z(angle), name=name)
    w = 2 * np.pi
    turn = JointMotion(position=lambda t: w * t, velocity=lambda t: w + 0 * t,
                       acceleration=lambda t: 0 * t)
    system = System(gravity=[0, -9.81, 0])
    system.add(bar("crank", 0.5, 0.5, 0.0), RevoluteJoint(axis=Z, drive=turn, name="O"))
    top = np.array([1.625, np.sqrt(1 - 0.125 ** 2), 0.0])     # the rocker's top at t = 0
    parent = "crank"
    for e in range(elements):
        name = f"c{e}"
        system.add(steel_rod(1.5 / elements, 0.008, name,
                             rotation=rot_z(np.arctan2(top[1], top[0] - 0.5))),
                   RevoluteJoint(axis=Z, name="A") if e == 0 else FixedHinge(), parent=parent)
        parent = name
    system.add(bar("rocker", 1.0, 1.0, np.arctan2(-top[1], 1.5 - top[0])),
               RevoluteJoint(axis=Z, name="B"), parent=parent)
    system.close(RevoluteJoint(axis=Z, name="C"), "rocker", "ground", at_b=[1.5, 0, 0])
    return assemble(system.build(), keep=["O"])


def mesh_mid_deflection(result, first, elements):
    """The mid-point's deflection from the chord of the link made of bodies first ..
    first + elements - 1 (an even count: the mid-point is an element's input point), along
    z x chord."""
    pa = result.position_input[:, first]
    pb = result.position_output[:, first + elements - 1]
    pm = result.position_input[:, first + elements // 2]
    e1 = (pb - pa) / np.linalg.norm(pb - pa, axis=1)[:, None]
    d = pm - 0.5 * (pa + pb)
    d -= np.sum(d * e1, axis=1)[:, None] * e1
    return np.sum(d * np.cross(Z, e1), axis=1)


def test_pinned_unit_beam_matches_closed_forms():
    """The estimate's Ritz problem with a pinned root and a pinned tip, in the input section's
    frame (the turn as a coordinate, the tip held on the root's line), converges to the simply
    supported beam's closed forms: first frequency pi^2 sqrt(EI / mu L^4), second 4 pi^2, mid
    deflection 5 q L^4 / 384 EI; clamped-pinned: 15.418 and q L^4 / 185 EI."""
    for family in (CLAMPED, CLAMPED_LOADED):
        cap = 10 if family == CLAMPED else 6
        (f1, f2, *_), d = _unit_beam_with_ends(family, cap, 0.0, True, True)
        assert f1 == pytest.approx(np.pi ** 2, rel=2e-4)
        assert f2 == pytest.approx(4 * np.pi ** 2, rel=2e-3)
        assert d == pytest.approx(5 / 384, rel=5e-4)    # (10 clamped-free shapes: 2e-4)
        (f1, *_), d = _unit_beam_with_ends(family, cap, 0.0, False, True)
        assert f1 == pytest.approx(15.4182, rel=2e-4)
        assert d == pytest.approx(1 / 184.6, rel=2e-3)


def test_revolute_root_counts_modes_for_a_pinned_root():
    """Behind a revolute joint the default keeps enough modes for a pinned root and says so."""
    model = double_pendulum()
    assert model.beam_ends[:2] == ((True, False), (True, False))
    assert all(model.beam_params[k, MODES] >= 4 for k in (0, 1))
    text = model.describe()
    assert "the root turns freely" in text and "second frequency" in text


def test_double_pendulum_of_beams_default_against_a_fine_mesh():
    """The planar double pendulum of two steel beams behind revolute joints, one element a
    link with the defaults, against 8 elements a link: the second beam's mid-point deflection
    within 5% of its peak at every instant (was 42%: 1.19 mm against 1.49 mm) and the tip within
    1% of its reach (2 m)."""
    t_end, dt = 0.8, 2e-4
    fine = simulate(double_pendulum(8), t_end, dt, record_dt=0.01)
    coarse_model = double_pendulum(1)
    coarse = simulate(coarse_model, t_end, dt, record_dt=0.01)
    reference = mesh_mid_deflection(fine, 8, 8)
    mid = beam_midpoint_deflection(coarse_model, coarse, 1)[:, 0]
    peak = np.abs(reference).max()
    assert 1.3e-3 < peak < 1.7e-3                 # the swing's bending, ~1.49 mm
    assert np.abs(mid - reference).max() < 0.05 * peak
    assert np.abs(coarse.position_output[:, -1] - fine.position_output[:, -1]).max() < 0.02
    # the same pendulum of one StrainRod a link with its defaults (2 strain modes: 42% off;
    # now 4 for the pinned root, measured 1.4% against 8 rods a link) against the beams' mesh
    rods_model = double_pendulum(1, steel_strain_rod)
    assert rods_model.rod_params[1, ROD_MODES] >= 4
    rods = simulate(rods_model, t_end, dt, record_dt=0.01)
    line = rod_centre_line(rods_model.rod_params[1], rods.modal_coordinates[:, 8:16], 3)
    points = rods.position_input[:, 1, None, :] + np.einsum("tij,tpj->tpi", rods.rotation[:, 1],
                                                             line)
    chord = points[:, 2] - points[:, 0]
    e1 = chord / np.linalg.norm(chord, axis=1)[:, None]
    d = points[:, 1] - 0.5 * (points[:, 0] + points[:, 2])
    d -= np.sum(d * e1, axis=1)[:, None] * e1
    rod_mid = np.sum(d * np.cross(Z, e1), axis=1)
    assert np.abs(rod_mid - reference).max() < 0.05 * peak


def test_four_bar_coupler_stiffened_by_default_against_a_fine_mesh():
    """A crank-rocker whose coupler is a steel beam in the loop: its ends move with the crank
    and the rocker, so the default keeps its geometric stiffening (to all orders: a pinned root
    with 4 modes) and the coupler's mid-point deflection is within 5% of the fine mesh's peak
    at every instant over a turn, the rocker angle within 1e-3 rad (the old default, 2 modes
    without stiffening: a 77 mm peak, 178% of the peak off, the rocker 2.1e-2 rad)."""
    model = crank_rocker(1)
    assert model.beam_params[1, STIFFENING] == EXACT
    t_end, dt = 1.0, 2e-4
    fine = simulate(crank_rocker(8), t_end, dt, record_dt=0.01)
    coarse = simulate(model, t_end, dt, record_dt=0.01)
    reference = mesh_mid_deflection(fine, 1, 8)
    mid = beam_midpoint_deflection(model, coarse, 1)[:, 0]
    peak = np.abs(reference).max()
    assert 0.02 < peak < 0.035                    # ~28 mm
    assert np.abs(mid - reference).max() < 0.05 * peak

    def rocker_angle(result):
        rot = result.rotation[:, -1]
        return np.unwrap(np.arctan2(rot[:, 1, 0], rot[:, 0, 0]))
    assert np.abs(rocker_angle(coarse) - rocker_angle(fine)).max() < 1e-3


def test_stiffening_off_only_where_the_loops_hold_the_chord():
    """A beam between two ground pivots (its chord held) keeps the stiffening off and says
    why; a four-bar's coupler (its ends free to approach) keeps it on."""
    beam = dict(length=1.0, bending_stiffness=100.0, mass_per_length=1.0,
                polar_inertia_per_length=1e-5)
    simply_supported = dttmm.build_chain([dttmm.BallJoint(), EulerBernoulliBeam(**beam)],
                                         tip="ball", gravity=[0, -9.81, 0])
    assert simply_supported.beam_params[0, STIFFENING] == 0.0
    system = System(gravity=[0, -9.81, 0])
    system.add(EulerBernoulliBeam(**beam, name="b"), RevoluteJoint(axis=Z))
    system.close(RevoluteJoint(axis=Z), "b", "ground")
    between_pivots = system.build()
    assert between_pivots.beam_params[0, STIFFENING] == 0.0
    assert between_pivots.beam_ends[0] == (True, True)
    assert "the loops hold this beam's chord" in between_pivots.describe()
    assert crank_rocker(1).beam_params[1, STIFFENING] != 0.0

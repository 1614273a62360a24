"""The modal beam against analytical results it did not compute."""
import numpy as np
import pytest

from dttmm import BallJoint, EulerBernoulliBeam, RigidBody, build_chain, simulate
from dttmm.model.chains import unit_link
from dttmm.results.result import beam_midpoint_deflection

SIDE, E, RHO, G = 0.02, 2.5e10, 3300.0, 9.81
EI = E * SIDE ** 4 / 12


def beam(**kw):
    # the paper's beam: these analytic answers are linear theory's.  (The stiff beam of
    # test_stiff_beam_moves_as_the_rigid_body, stiffened, leaves the rigid body by 6.0e-7 m at
    # dt = 1e-3 and 1.4e-7 at 5e-4, order 2.1: the trapezoidal rule rings its 13.7 kHz modes,
    # and the foreshortening's eta'^2 terms pass that to the frame; 1.2e-8 unstiffened.)
    args = dict(length=1.0, density=RHO, area=SIDE ** 2, bending_stiffness=EI,
                polar_inertia_per_length=RHO * SIDE ** 4 / 6, stiffening=False)
    args.update(kw)
    return EulerBernoulliBeam(**args)


@pytest.mark.parametrize("modes, tol", [(1, 5e-3), (3, 1e-3)])
def test_simply_supported_static_sag(modes, tol):
    """Ball joints to the ground at both ends, gravity, modal damping: the mid-span deflection
    settles to 5 q L^4 / (384 EI).  One sine mode gives 4 q L^4 / (pi^5 EI) (0.39% high), three
    modes 0.03% low: the tolerance follows the modal truncation."""
    model = build_chain([BallJoint(), beam(modes_per_plane=modes, damping_ratio=0.2)], tip="ball")
    res = simulate(model, 1.0, 1e-3, record_every=10)
    sag = beam_midpoint_deflection(model, res, 0)[-1]
    q = RHO * SIDE ** 2 * G
    exact = 5 * q / (384 * EI)
    assert sag[0] == pytest.approx(-exact, rel=tol)
    assert abs(sag[1]) < 1e-12
    assert np.allclose(res.force[-1, 0], [0.0, q / 2, 0.0], atol=1e-9)      # half the weight


def test_stiff_beam_moves_as_the_rigid_body():
    """EI x 3e5: the three-pendulum with the beam behaves as with a rigid body of the same mass
    and inertia about the input point, diag(j_p L, mu L^3/3, mu L^3/3)."""
    mu = RHO * SIDE ** 2
    rigid = RigidBody(mass=mu, inertia=[RHO * SIDE ** 4 / 6, mu / 3, mu / 3],
                      inertia_about="input", to_mass_center=[0.5, 0, 0], to_output=[1, 0, 0])
    runs = []
    for middle in (beam(bending_stiffness=3e5 * EI), rigid):
        model = build_chain([BallJoint(), unit_link(), BallJoint(), middle, BallJoint(),
                             unit_link(angular_velocity=[0, 0.1, 0])])
        runs.append(simulate(model, 1.0, 1e-3, record_every=100))
    assert np.abs(runs[0].position_output - runs[1].position_output).max() < 1e-7

"""Bad input raises ValueError at build time, naming the element and the argument; a diverging
run stops with the step and the cause."""
import numpy as np
import pytest

from dttmm import (BallJoint, DivergenceError, ElasticHinge, FixedHinge, RigidBody, build_chain,
                   simulate)
from dttmm.model.chains import rigid_chain, unit_link


def body(**kw):
    args = dict(mass=1.0, inertia=[0.1, 0.2, 0.2], inertia_about="mass_center",
                to_mass_center=[0.5, 0, 0], to_output=[1, 0, 0])
    args.update(kw)
    return RigidBody(**args)


@pytest.mark.parametrize("kwargs, words", [
    (dict(mass=0.0), ["body 1", "mass"]),
    (dict(mass=-2.0), ["body 1", "mass"]),
    (dict(mass=float("nan")), ["body 1", "mass"]),
    (dict(inertia=[[0.1, 0.05, 0], [0.0, 0.2, 0], [0, 0, 0.2]]),
     ["body 1", "inertia", "symmetric"]),
    (dict(inertia=[0.1, -0.2, 0.2]), ["body 1", "inertia", "positive definite"]),
    (dict(inertia=[0.1, 0.1, 0.5]), ["body 1", "inertia", "triangle"]),
    (dict(inertia=[0.1, np.inf, 0.2]), ["body 1", "inertia"]),
    (dict(to_output=[1, np.nan, 0]), ["body 1", "to_output"]),
    (dict(to_mass_center=[1, 2]), ["body 1", "to_mass_center"]),
    (dict(inertia_about="centroid"), ["body 1", "inertia_about"]),
    (dict(angular_velocity=[0, np.nan, 0]), ["body 1", "angular_velocity"]),
    (dict(rotation=np.diag([1.0, 1.0, -1.0])), ["body 1", "rotation"]),
    (dict(force=lambda t: [0.0, np.nan, 0.0]), ["body 1", "force"]),
])
def test_bad_body_parameters_name_body_and_argument(kwargs, words):
    with pytest.raises(ValueError) as err:
        build_chain([BallJoint(), body(), BallJoint(), body(**kwargs)])
    for w in words:
        assert w in str(err.value)


def test_named_body_is_named():
    with pytest.raises(ValueError, match="'forearm'.*mass"):
        build_chain([BallJoint(), body(name="forearm", mass=0)])


@pytest.mark.parametrize("hinge, words", [
    (ElasticHinge(translational_stiffness=-1.0, rotational_stiffness=1.0),
     ["ElasticHinge", "hinge 1", "translational_stiffness"]),
    (ElasticHinge(translational_stiffness=1.0, rotational_stiffness=[1, 0, 1]),
     ["ElasticHinge", "hinge 1", "rotational_stiffness"]),
    (ElasticHinge(1.0, 1.0, rotational_damping=-1.0), ["hinge 1", "rotational_damping"]),
    (ElasticHinge(1.0, np.nan), ["hinge 1", "rotational_stiffness"]),
    (ElasticHinge(1.0, 1.0, deflection=[0.0, np.inf, 0.0]), ["hinge 1", "deflection"]),
    (ElasticHinge(1.0, 1.0, deflection=[0.0, 1.0]), ["hinge 1", "deflection"]),
    (FixedHinge(rotation=np.ones((3, 3))), ["FixedHinge", "hinge 1", "rotation"]),
])
def test_bad_hinge_parameters(hinge, words):
    with pytest.raises(ValueError) as err:
        build_chain([BallJoint(), body(), hinge, body()])
    for w in words:
        assert w in str(err.value)


def test_empty_chain_and_bad_structure():
    with pytest.raises(ValueError, match="empty"):
        build_chain([])
    with pytest.raises(ValueError, match="alternate"):
        build_chain([BallJoint(), body(), BallJoint()])
    with pytest.raises(ValueError, match="element 0 must be a hinge"):
        build_chain([body(), BallJoint()])
    with pytest.raises(ValueError, match="gravity"):
        build_chain([BallJoint(), body()], gravity=[0, np.inf, 0])


def test_singular_ball_joint_lookahead_is_caught_at_build_time():
    # between two ball joints the body's moment equation has the matrix J_I + M l_IO^ l_IC^;
    # with l_IC = [0.5, 0, 0], l_IO = [1, 0, 0] it is J_C + M diag(0, -1/4, -1/4): singular when
    # J_C,yy = M / 4 (the output point is the centre of percussion for the input point)
    rod = RigidBody(mass=1.0, inertia=[0.1, 0.25, 0.2], inertia_about="mass_center",
                    to_mass_center=[0.5, 0, 0], to_output=[1, 0, 0], name="rod")
    with pytest.raises(ValueError, match="'rod'.*look-ahead is singular"):
        build_chain([BallJoint(), unit_link(), BallJoint(), rod, BallJoint(), unit_link()])


def test_fixed_hinge_contradiction():
    with pytest.raises(ValueError, match="body 1.*angular_velocity.*fixed hinge"):
        build_chain([BallJoint(), body(), FixedHinge(), body(angular_velocity=[1, 0, 0])])


@pytest.mark.parametrize("kwargs, word", [
    (dict(dt=0.0), "dt"), (dict(dt=-1e-3), "dt"), (dict(dt=np.nan), "dt"),
    (dict(t_end=0.0), "t_end"), (dict(method="euler"), "method"), (dict(rho_inf=1.5), "rho_inf"),
    (dict(record_every=0), "record_every"), (dict(newton_iterations=-1), "newton_iterations"),
])
def test_bad_solver_arguments(kwargs, word):
    args = dict(t_end=0.1, dt=1e-3)
    args.update(kwargs)
    with pytest.raises(ValueError, match=word):
        simulate(rigid_chain(2), args.pop("t_end"), args.pop("dt"), **args)


def test_diverging_run_stops_with_step_and_cause():
    """A torque growing without bound makes the chain spin up: the step's error estimate stops
    it at once; without that guard, the state overflows and NaN stops it."""
    spinning = unit_link(torque=lambda t: [0.0, 0.0, 1e300 * t])
    with pytest.raises(DivergenceError, match="step 1 .*local error estimate"):
        simulate(build_chain([BallJoint(), spinning]), 1.0, 1e-2)
    with pytest.raises(DivergenceError) as err:
        simulate(build_chain([BallJoint(), spinning]), 1.0, 1e-2, max_step_error=None)
    assert "step" in str(err.value) and "NaN or infinite" in str(err.value)
    assert err.value.step >= 1


def test_inconsistent_prescribed_motion():
    from dttmm import Ground, PrescribedMotion
    bad = PrescribedMotion.spin_about_axis([0, 0, 1], angle=lambda t: t * t, rate=lambda t: t,
                                           acceleration=lambda t: 1.0)     # rate should be 2 t
    with pytest.raises(ValueError, match="PrescribedMotion: angular_velocity"):
        build_chain([FixedHinge(), body()], ground=Ground(motion=bad))


def test_direct_mode_fails_loudly_on_a_long_chain():
    """Multiplying out 30 link matrices that hold M/(beta dt^2) loses every digit (notes §5): the
    run must stop with a clear message, not return garbage; Riccati runs the same chain."""
    model = rigid_chain(30)
    with pytest.raises(DivergenceError, match="riccati"):
        simulate(model, 0.01, 1e-3, method="direct")
    res = simulate(model, 0.01, 1e-3)
    assert np.all(np.isfinite(res.position_output))


def test_the_model_is_read_only_and_the_kernels_see_writable_arrays():
    """A negative mass written after build() must not simulate: the model's arrays refuse the
    write.  The solvers hand their kernels writable arrays (the model's own memory behind its
    read-only views, model.kernel_array, or copies), so no kernel is compiled a second time
    for read-only arrays (numba types them apart), also after a run's checkpoint has made its
    own arrays read-only (a second run of each model)."""
    from dttmm import simulate_reference
    from dttmm.model.chains import arm, three_pendulum
    from dttmm.kernels import python_twin
    from dttmm.kernels.stepping import loop, step as kstep
    from dttmm.reference import equations
    for model in (three_pendulum(), arm("motion")):
        with pytest.raises(ValueError, match="read-only"):
            model.body_params[0, 0] = -1.0
        with pytest.raises(ValueError, match="read-only"):
            model.gravity[1] = 0.0
        simulate(model, 0.01, 1e-3)
        simulate(model, 0.01, 1e-3)
        simulate_reference(model, 0.01, rtol=1e-6, atol=1e-6)
    kernels = list(loop._SKELETONS.values()) + [kstep.initial_accelerations,
                                                equations.rhs_kernel,
                                                python_twin(equations.rhs_kernel),
                                                equations._solve_dynamics]
    for kernel in kernels:
        for signature in getattr(kernel, "signatures", []):
            assert "readonly" not in str(signature), (kernel, signature)


def test_motions_defined_from_t_0_on_are_accepted():
    """A prescribed joint motion defined for t >= 0 only: the derivative checks use forward
    differences at t = 0 (they called it at t = -1e-5 s), and still catch a wrong derivative
    there."""
    from dttmm import JointMotion, RevoluteJoint, System
    from dttmm.model.chains import unit_link

    def angle(t):
        assert t >= 0.0, "called before t = 0"
        return t * t

    def system(rate):
        s = System()
        s.add(unit_link(name="arm"),
              RevoluteJoint(axis=[0, 0, 1], drive=JointMotion(angle, rate, lambda t: 2.0)))
        return s

    system(lambda t: 2.0 * t).build()
    with pytest.raises(ValueError, match="velocity"):
        system(lambda t: 2.0 * t + 1.0).build()


def test_a_bad_number_and_a_zero_spin_axis_name_their_element():
    from dttmm import EulerBernoulliBeam, PrescribedMotion
    beam = EulerBernoulliBeam(length=1.0, density=1.0, area=1.0, bending_stiffness="stiff",
                              polar_inertia_per_length=1.0, name="tube")
    with pytest.raises(ValueError, match="tube.*bending_stiffness must be a number"):
        build_chain([FixedHinge(), beam])
    with pytest.raises(ValueError, match="spin_about_axis: axis must be nonzero"):
        PrescribedMotion.spin_about_axis([0, 0, 0], lambda t: t, lambda t: 1.0, lambda t: 0.0)


def test_a_ground_position_beside_a_motion_is_refused():
    """Ground(position=..., motion=...) used to drop the position silently."""
    from dttmm import Ground, PrescribedMotion
    hub = PrescribedMotion.spin_about_axis([0, 0, 1], lambda t: t, lambda t: 1.0, lambda t: 0.0)
    for ground in (Ground(position=[0.0, 1.0, 0.0], motion=hub),
                   Ground(rotation=np.eye(3), motion=hub)):
        with pytest.raises(ValueError, match="Ground: with a motion"):
            build_chain([FixedHinge(), body()], ground=ground)
    build_chain([FixedHinge(), body()], ground=Ground(motion=hub))

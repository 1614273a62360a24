"""dttmm: the discrete-time transfer matrix method for multibody systems of rigid bodies and
flexible beams (Rui et al.), with an independent Newton-Euler reference solver."""
from importlib.metadata import PackageNotFoundError, version as _version

from .elements import (BallJoint, Box, Capsule, Contact, CylindricalJoint, ElasticHinge,
                       EulerBernoulliBeam, FixedHinge, FreeJoint, JointForce, JointLimit,
                       JointMotion, PDTracking, Plane, Sphere,
                       PlanarJoint, PrismaticJoint, RevoluteJoint, RigidBody, SpringDamper,
                       StrainRod, UniversalJoint)
from .model.assembly import assemble
from .model.loop_kinematics import loop_residuals
from .solving.dynamics import forward_dynamics, linearize, ode
from .model.model import Ground, Model, PrescribedMotion
from .model.system import System, build_chain
from .results.recording import Checkpoint
from .results.result import Result
from .solving.run_checks import DivergenceError, UnresolvedMotionWarning
from .solving.solver import load_stream, simulate
from .solving.statics import StaticEquilibrium, StaticEquilibriumError, static_equilibrium
from .reference import simulate_reference
from .interfaces.parameter_sweep import SweepTable, sweep
# (Model.describe's words, set on import: model/model.py::DESCRIBE)
from .interfaces import describe as _describe  # noqa: F401

try:
    __version__ = _version("dttmm")
except PackageNotFoundError:        # run from a source tree that is not installed
    __version__ = "0.0.0+unknown"

__all__ = ["RigidBody", "EulerBernoulliBeam", "StrainRod", "BallJoint", "FixedHinge",
           "ElasticHinge", "FreeJoint", "RevoluteJoint", "UniversalJoint", "PrismaticJoint",
           "CylindricalJoint", "PlanarJoint", "JointLimit", "JointForce", "Sphere", "Capsule",
           "Box", "Contact", "Plane", "SpringDamper", "JointMotion", "PDTracking", "Ground",
           "PrescribedMotion", "Model",
           "System", "build_chain", "assemble", "loop_residuals", "forward_dynamics", "ode",
           "linearize", "simulate", "simulate_reference", "load_stream", "Result", "Checkpoint",
           "DivergenceError", "UnresolvedMotionWarning", "static_equilibrium",
           "StaticEquilibrium", "StaticEquilibriumError", "sweep", "SweepTable", "__version__"]

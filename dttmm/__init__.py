"""dttmm: the discrete-time transfer matrix method for multibody chains."""
from .elements import (BallJoint, ElasticHinge, EulerBernoulliBeam, FixedHinge, JointForce,
                       JointMotion, PrismaticJoint, RevoluteJoint, RigidBody, SpringDamper,
                       UniversalJoint)
from .model import Ground, Model, PrescribedMotion, System, build_chain

__all__ = ["RigidBody", "EulerBernoulliBeam", "BallJoint", "FixedHinge", "ElasticHinge",
           "RevoluteJoint", "UniversalJoint", "PrismaticJoint", "JointForce", "SpringDamper",
           "JointMotion", "Ground", "PrescribedMotion", "Model", "System", "build_chain"]
from .solver import DivergenceError, simulate  # noqa: E402

__all__ += ["simulate", "DivergenceError"]

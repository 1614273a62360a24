"""The element library: bodies and hinges, each a small declarative class."""
from .beam import EulerBernoulliBeam
from .hinges import BALL, ELASTIC, FIXED, BallJoint, ElasticHinge, FixedHinge
from .rigid_body import RigidBody

RIGID, BEAM = 0, 1      # Model.body_kind

__all__ = ["RigidBody", "EulerBernoulliBeam", "BallJoint", "FixedHinge", "ElasticHinge", "BALL",
           "FIXED", "ELASTIC", "RIGID", "BEAM"]

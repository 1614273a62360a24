"""The element library: bodies and joints, each a small declarative class, and their kinds
declared once (kinds.py)."""
from .beam import EulerBernoulliBeam
from .hinges import BALL, ELASTIC, FIXED, BallJoint, ElasticHinge, FixedHinge
from .kinds import BEAM, BODY_KINDS, JOINT_KINDS, RIGID
from .rigid_body import RigidBody

__all__ = ["RigidBody", "EulerBernoulliBeam", "BallJoint", "FixedHinge", "ElasticHinge", "BALL",
           "FIXED", "ELASTIC", "RIGID", "BEAM", "BODY_KINDS", "JOINT_KINDS"]

"""The element library: bodies and hinges, each a small declarative class."""
from .hinges import BALL, ELASTIC, FIXED, BallJoint, ElasticHinge, FixedHinge
from .rigid_body import RigidBody

__all__ = ["RigidBody", "BallJoint", "FixedHinge", "ElasticHinge", "BALL", "FIXED", "ELASTIC"]

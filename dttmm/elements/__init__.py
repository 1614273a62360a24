"""The element library: bodies and joints, each a small declarative class, and their kinds
declared once (kinds.py)."""
from .beam import EulerBernoulliBeam
from .contact import Box, Capsule, Contact, Plane, Sphere
from .drives import JointForce, JointMotion, PDTracking, SpringDamper
from .hinges import BALL, ELASTIC, FIXED, FREE, BallJoint, ElasticHinge, FixedHinge, FreeJoint
from .joints import (PRISMATIC, REVOLUTE, UNIVERSAL, CylindricalJoint, PlanarJoint,
                     PrismaticJoint, RevoluteJoint, UniversalJoint)
from .kinds import BEAM, BODY_KINDS, JOINT_KINDS, RIGID, ROD
from .limits import JointLimit
from .rigid_body import RigidBody
from .strain_rod import StrainRod

__all__ = ["RigidBody", "EulerBernoulliBeam", "StrainRod", "BallJoint", "FixedHinge",
           "ElasticHinge", "FreeJoint", "RevoluteJoint", "UniversalJoint", "PrismaticJoint",
           "CylindricalJoint", "PlanarJoint", "JointLimit", "JointForce", "Sphere", "Capsule",
           "Box", "Contact", "Plane",
           "SpringDamper", "JointMotion", "PDTracking", "BALL", "FIXED", "ELASTIC", "FREE",
           "REVOLUTE", "UNIVERSAL", "PRISMATIC", "RIGID", "BEAM", "ROD", "BODY_KINDS",
           "JOINT_KINDS"]

"""The model's row offsets and the shape constants' rows, as plain ints for the reference's kernels
(the reference's formulation: newton_euler.py)."""
from ..elements import BEAM, RIGID, ROD
from ..elements.beam import (DAMPING_RATIO, EI_V, EI_W, GJ, LENGTH, LOAD_AXES, MASS_PER_LENGTH,
                             MODES, POLAR_PER_LENGTH, STIFFENING, TORSION_MODES, AXIAL_MODES, EA)
from ..elements.drives import FORCE, SPRING_DAMPER
from ..elements.hinges import (C_ROTATION, C_TRANSLATION, K_ROTATION, K_TRANSLATION,
                               REST_ROTATION)
from ..elements.kinds import (ANGLE_A, ANGLE_B, AXIS, AXIS_START, CHILD, COORDINATES, DOT, FRAME,
                             GAP_A, GAP_WORLD, HAS_SLIDES, MAX_COORDINATES, MOTION, ROTATION_A,
                             SLIDE, TURN, UNDECLARED_BODY_KIND, WITH_COORDINATES)
from ..elements.rigid_body import INERTIA_INPUT, MASS, TO_MASS_CENTER, TO_OUTPUT


# offsets into a body_params / hinge_params row, as plain ints for the kernels
_MASS = MASS
_LIC = TO_MASS_CENTER.start
_LIO = TO_OUTPUT.start
_JI = INERTIA_INPUT.start
_R0 = REST_ROTATION.start
_KT = K_TRANSLATION.start
_CT = C_TRANSLATION.start
_KR = K_ROTATION.start
_CR = C_ROTATION.start
_RIGID = RIGID
_BEAM = BEAM
_ROD = ROD
_UNDECLARED_BODY_KIND = UNDECLARED_BODY_KIND     # (what the kernels raise on another code)
_DOT, _GAP_A, _GAP_WORLD, _ANGLE_A, _ANGLE_B, _ROTATION_A = (DOT, GAP_A, GAP_WORLD, ANGLE_A,
                                                            ANGLE_B, ROTATION_A)
_SPRING_DAMPER = SPRING_DAMPER
_FORCE = FORCE
_BL, _BMU, _BEIV, _BEIW = LENGTH, MASS_PER_LENGTH, EI_V, EI_W
_BJP, _BZETA, _BMODES, _BSTIFF = POLAR_PER_LENGTH, DAMPING_RATIO, MODES, STIFFENING
_BTWIST, _BGJ, _BAXES = TORSION_MODES, GJ, LOAD_AXES
_BSTRETCH, _BEA = AXIAL_MODES, EA
# the joints' declarations (elements/kinds.py): per kind its coordinates' count, and per
# coordinate its motion (a turn or a slide), its axis's slot and the frame that axis is fixed in
_N_COORDINATES, _MAXC = COORDINATES, MAX_COORDINATES
_MOTION, _AXIS, _FRAME, _AXIS_START = MOTION, AXIS, FRAME, AXIS_START
_TURN, _SLIDE, _CHILD, _HAS_SLIDES = TURN, SLIDE, CHILD, HAS_SLIDES
JOINTS_WITH_COORDINATES = WITH_COORDINATES          # (elements/kinds.py)

# rows of the per-beam shape constants (_Problem.shape_vec[k, row, mode])
_SY, _TY, _YL, _DYL, _MF, _KF = range(6)
N_SHAPE_ROWS = 6

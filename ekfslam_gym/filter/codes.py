"""Codes shared by the compiled filter kernels and their Python wrapper (plain ints: numba reads them as
compile-time constants, and the wrapper needs them without loading numba).

Status: OK, NOT_PD (an innovation covariance not positive definite), BAD_ID (a landmark index outside
[0, n)), BAD_INPUT (a non-finite control, noise or reading). Motion models: odometry, velocity, wheels.
Variants: the standard EKF, first-estimates Jacobians (FEJ), the iterated correction (IEKF).
"""

OK = 0
NOT_PD = 1
BAD_ID = 2
BAD_INPUT = 3

MODEL_ODOMETRY = 0
MODEL_VELOCITY = 1
MODEL_WHEELS = 2

VARIANT_EKF = 0
VARIANT_FEJ = 1
VARIANT_IEKF = 2

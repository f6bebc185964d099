"""Innovation statistics of one correction, compiled: the NIS of each reading and the joint likelihood.

For the readings z (k, 2) of initialised landmarks, from the state before their correction: the innovations
nu = z - h(mu) (bearing wrapped), their joint covariance S = H Sigma H^T + I_k (x) Q, each reading's NIS
nu_i^T S_ii^-1 nu_i (chi^2 with 2 dof when the filter is consistent), and log N(nu; 0, S), the term of the
prediction-error decomposition of the likelihood (``calibration``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..angles import compiled_wrap_angle as wrap_angle
from ..filter.models import range_bearing_into

__all__ = ["group_innovations"]


@njit(cache=True)
def group_innovations(mean, cov, slots, z, Q, min_range):
    """Per-reading NIS (2 dof) and the joint log N(nu; 0, S) of the readings ``z`` (k, 2) of the initialised
    ``slots`` (k,), from the state (``mean``, ``cov``) before their correction."""
    k = slots.shape[0]
    n = 3 + 2 * k
    index = np.empty(n, np.int64)
    index[:3] = np.arange(3)
    H = np.zeros((2 * k, n))
    nu = np.empty(2 * k)
    hx = np.empty((2, 3))
    hm = np.empty((2, 2))
    for row in range(k):
        j = 3 + 2 * slots[row]
        index[3 + 2 * row] = j
        index[4 + 2 * row] = j + 1
        r, bearing = range_bearing_into(mean[:3], mean[j : j + 2], min_range, hx, hm)
        H[2 * row : 2 * row + 2, :3] = hx
        H[2 * row : 2 * row + 2, 3 + 2 * row : 5 + 2 * row] = hm
        nu[2 * row] = z[row, 0] - r
        nu[2 * row + 1] = wrap_angle(z[row, 1] - bearing)
    block = np.empty((n, n))
    for a in range(n):
        for b in range(n):
            block[a, b] = cov[index[a], index[b]]
    S = H @ block @ H.T
    for row in range(k):
        S[2 * row : 2 * row + 2, 2 * row : 2 * row + 2] += Q
    chol = np.linalg.cholesky(S)
    white = np.linalg.solve(chol, nu)
    log_like = -0.5 * np.dot(white, white) - np.sum(np.log(np.diag(chol))) - k * math.log(2.0 * math.pi)
    nis = np.empty(k)
    for row in range(k):
        s00 = S[2 * row, 2 * row]
        s01 = S[2 * row, 2 * row + 1]
        s11 = S[2 * row + 1, 2 * row + 1]
        v0 = nu[2 * row]
        v1 = nu[2 * row + 1]
        nis[row] = (s11 * v0 * v0 - 2.0 * s01 * v0 * v1 + s00 * v1 * v1) / (s00 * s11 - s01 * s01)
    return nis, log_like

"""Compiled EKF-SLAM kernels: prediction, correction and landmark initialisation, in place.

Why compiled: one numpy call costs a few microseconds whatever its size at these dimensions, and the env calls
the filter millions of times (docs/performance.md). Each kernel touches only what changes:
prediction the three pose rows and columns (O(N)); correction the N x 2m block Sigma H^T and the rank-2m
update of Sigma (O(m N^2)); no G, F_x, F_x,j or H of full size is ever built.

The log-determinant of Sigma is kept exactly by the identities in docs/filter-and-graph.md's "The maths, briefly", using P, the pose covariance
conditioned on the map (the Schur complement of the map block):
- prediction:  P <- G P G^T + R,               d log det = log det P' - log det P
- correction:  P^-1 <- P^-1 + sum Hx^T Q^-1 Hx,  d log det = sum log det Q - log det S
- inverse init: P^-1 <- P^-1 + Gr^T T^-1 Gr,     d log det = log det T - log det(prior block), T = Gz Q Gz^T

The variants change only where the Jacobians are taken, never the algebra above, so the bookkeeping stays exact
for each: EKF at the current estimate; FEJ (first-estimates Jacobians, Huang, Mourikis & Roumeliotis, IJRR 2010)
at the pose's prediction and each landmark's first estimate; IEKF (iterated correction) at Gauss-Newton iterates,
each iteration O(m N), the covariance updated once with the last H.

Status codes returned to the Python wrapper: OK, NOT_PD (innovation covariance not positive definite),
BAD_ID (a landmark index outside [0, n)), BAD_INPUT (a non-finite control, noise or reading).
"""

from __future__ import annotations

import math
from typing import TypeAlias

import numpy as np
from numba import njit

from ..kernel_types import BoolArray1, F8Array1, F8Array2, F8Array3, I8Array1
from .codes import BAD_ID, BAD_INPUT, MODEL_ODOMETRY, MODEL_WHEELS, NOT_PD, OK, VARIANT_FEJ, VARIANT_IEKF
from .models import (
    inverse_range_bearing,
    odometry_motion,
    range_bearing_into,
    velocity_motion,
    wheel_motion,
    wrap_angle,
)

# The iterated correction stops once a Gauss-Newton step moves no state entry by more than this (m or rad).
ITERATION_TOLERANCE = 1e-9

# The exported kernels take the filter's arrays and its fixed options as two tuples, which ``EKFSLAM`` builds
# once, rather than as a dozen arguments each (a call costs the same: the tuples are unpacked item by item, and
# each array unboxed costs the call ~0.8k instructions, so the bundle holds only what every filter call reads).
# FilterArrays: mean (N,), cov (N, N), P (3, 3) (the pose covariance given the map), observed (n,), prior_pose
# (3,) (the pose as the last prediction left it), first (n, 2) (each landmark's first estimate), G_used (3, 3),
# H_used (>= m, 2, 5) and H_slots (>= m,) (the Jacobians last used).
FilterArrays: TypeAlias = (
    "tuple[F8Array1, F8Array2, F8Array2, BoolArray1, F8Array1, F8Array2, F8Array2, F8Array3, I8Array1]"
)
# FilterOptions: motion model code, dt (s, velocity model), wheel base (m, wheels model), min_range (m), course
# initialisation, sequential update, variant code, iterations (iekf).
FilterOptions: TypeAlias = "tuple[int, float, float, float, bool, bool, int, int]"


@njit(cache=True)
def det3(a: np.ndarray) -> float:
    return (
        a[0, 0] * (a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1])
        - a[0, 1] * (a[1, 0] * a[2, 2] - a[1, 2] * a[2, 0])
        + a[0, 2] * (a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0])
    )


@njit(cache=True)
def inv3(a: np.ndarray) -> np.ndarray:
    """Inverse of a 3x3 matrix by cofactors (symmetric input gives symmetric output)."""
    out = np.empty((3, 3))
    out[0, 0] = a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]
    out[0, 1] = a[0, 2] * a[2, 1] - a[0, 1] * a[2, 2]
    out[0, 2] = a[0, 1] * a[1, 2] - a[0, 2] * a[1, 1]
    out[1, 0] = a[1, 2] * a[2, 0] - a[1, 0] * a[2, 2]
    out[1, 1] = a[0, 0] * a[2, 2] - a[0, 2] * a[2, 0]
    out[1, 2] = a[0, 2] * a[1, 0] - a[0, 0] * a[1, 2]
    out[2, 0] = a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]
    out[2, 1] = a[0, 1] * a[2, 0] - a[0, 0] * a[2, 1]
    out[2, 2] = a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]
    d = a[0, 0] * out[0, 0] + a[0, 1] * out[1, 0] + a[0, 2] * out[2, 0]
    for i in range(3):
        for j in range(3):
            out[i, j] /= d
    return out


@njit(cache=True)
def logdet2(a: np.ndarray) -> float:
    return math.log(a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0])


@njit(cache=True)
def inv2(a: np.ndarray) -> np.ndarray:
    d = a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]
    out = np.empty((2, 2))
    out[0, 0] = a[1, 1] / d
    out[1, 1] = a[0, 0] / d
    out[0, 1] = -a[0, 1] / d
    out[1, 0] = -a[1, 0] / d
    return out


@njit(cache=True)
def sandwich(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """A B A^T by plain loops: for these 2x2 and 3x3 sizes a BLAS call costs more than the arithmetic."""
    rows = A.shape[0]
    inner = A.shape[1]
    AB = np.zeros((rows, inner))
    for i in range(rows):
        for j in range(inner):
            v = 0.0
            for p in range(inner):
                v += A[i, p] * B[p, j]
            AB[i, j] = v
    out = np.empty((rows, rows))
    for i in range(rows):
        for j in range(rows):
            v = 0.0
            for p in range(inner):
                v += AB[i, p] * A[j, p]
            out[i, j] = v
    return out


@njit(cache=True)
def sandwich_t(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """A^T B A by plain loops."""
    return sandwich(A.T.copy(), B)


@njit(cache=True)
def _symmetric_3x3(a: np.ndarray) -> None:
    for i in range(3):
        for j in range(i + 1, 3):
            m = 0.5 * (a[i, j] + a[j, i])
            a[i, j] = m
            a[j, i] = m


@njit(cache=True)
def predict(
    arrays: FilterArrays, options: FilterOptions, control: F8Array1, noise: F8Array2, noise_in_control_space: bool,
    track: bool,
) -> tuple[float, int]:  # fmt: skip
    """Prediction with ``control`` and its noise (see ``_predict``)."""
    mean, cov, P, _, prior_pose, _, G_used, _, _ = arrays
    model, dt, wheel_base, _, _, _, variant, _ = options
    return _predict(
        mean, cov, P, model, control, dt, wheel_base, noise, noise_in_control_space, track, prior_pose,
        variant == VARIANT_FEJ, G_used,
    )  # fmt: skip


@njit(cache=True)
def _predict(
    mean, cov, P, model, control, dt, wheel_base, noise, noise_in_control_space, track, prior_pose, fej, G_used,
):  # fmt: skip
    """Move the pose by the motion model; update the pose rows/columns of cov and, if tracking, P.

    ``noise`` is R (3x3, pose space) or, with ``noise_in_control_space``, M (control space) giving R = V M V^T.
    ``prior_pose`` (3,) holds the pose as the last prediction left it (its first estimate, before any
    correction); with ``fej`` the Jacobian's heading column is taken from it instead of the current estimate,
    G[:2, 2] = J (p_{k+1|k} - p_{k|k-1}) (Huang, Mourikis & Roumeliotis 2010), which keeps the linearised
    system's unobservable rotation unobservable. It is then set to the predicted pose. The G used is written
    to ``G_used`` (3, 3). Returns (change of log det Sigma (0.0 when not tracking), status).
    """
    if model == MODEL_ODOMETRY:
        new_pose, G, V = odometry_motion(mean[:3], control[0], control[1], control[2])
    elif model == MODEL_WHEELS:
        new_pose, G, V = wheel_motion(mean[:3], control[0], control[1], control[2], wheel_base)
    else:
        new_pose, G, V = velocity_motion(mean[:3], control[0], control[1], dt)
    for i in range(noise.shape[0]):
        for j in range(noise.shape[1]):
            if not math.isfinite(noise[i, j]):
                return 0.0, BAD_INPUT
    for i in range(3):
        if not math.isfinite(control[i]):
            return 0.0, BAD_INPUT
    if noise_in_control_space:
        R = sandwich(V, noise)
    else:
        R = noise.copy()
    _symmetric_3x3(R)
    if fej:
        G[0, 2] = -(new_pose[1] - prior_pose[1])
        G[1, 2] = new_pose[0] - prior_pose[0]
    G_used[:, :] = G
    mean[0] = new_pose[0]
    mean[1] = new_pose[1]
    mean[2] = new_pose[2]
    prior_pose[0] = new_pose[0]
    prior_pose[1] = new_pose[1]
    prior_pose[2] = new_pose[2]

    pose_block = sandwich(G, cov[:3, :3].copy()) + R
    _symmetric_3x3(pose_block)
    n = mean.shape[0]
    for c in range(3, n):
        a0 = cov[0, c]
        a1 = cov[1, c]
        a2 = cov[2, c]
        for r in range(3):
            v = G[r, 0] * a0 + G[r, 1] * a1 + G[r, 2] * a2
            cov[r, c] = v
            cov[c, r] = v
    cov[:3, :3] = pose_block

    if not track:
        return 0.0, OK
    new_P = sandwich(G, P) + R
    _symmetric_3x3(new_P)
    delta = math.log(det3(new_P)) - math.log(det3(P))
    P[:, :] = new_P
    return delta, OK


@njit(cache=True)
def _cholesky_in_place(S: np.ndarray) -> bool:
    """Lower Cholesky factor of S written into S (upper part zeroed); False if S is not positive definite."""
    k = S.shape[0]
    for j in range(k):
        d = S[j, j]
        for p in range(j):
            d -= S[j, p] * S[j, p]
        if not d > 0.0:
            return False
        d = math.sqrt(d)
        S[j, j] = d
        for i in range(j + 1, k):
            v = S[i, j]
            for p in range(j):
                v -= S[i, p] * S[j, p]
            S[i, j] = v / d
        for i in range(j):
            S[i, j] = 0.0
    return True


@njit(cache=True)
def _update(
    mean, cov, P, slots, readings, Q, Q_inv, logdet_Q, min_range, track, variant, iterations, prior_pose, first,
    H_used, H_slots, offset,
):  # fmt: skip
    """One correction with the given readings of already-initialised landmarks.

    Sigma <- Sigma - W W^T with W = (Sigma H^T) L^-T, S = L L^T: algebraically the course's (I - K H) Sigma,
    exactly symmetric (each entry sums the same products in the same order) and O(m N^2). Every loop over N
    runs along contiguous rows (H Sigma, W^T and Sigma's rows), which the compiler vectorises. Where H is
    taken: EKF, at the current mean; FEJ, at ``prior_pose`` and each landmark's first estimate (``first``), the
    innovation still at the current mean; IEKF, at Gauss-Newton iterates x_i (up to ``iterations``
    linearisations, x_{i+1} = mean + K_i (z - h(x_i) - H_i (mean - x_i)), each O(m N)), then the covariance
    once with the last H. The H used are written to ``H_used[offset:]`` ((2, 5) each: pose then landmark
    columns) and their slots to ``H_slots[offset:]``.
    Returns (change of log det Sigma, status).
    """
    m = slots.shape[0]
    if m == 0:
        return 0.0, OK
    n = mean.shape[0]
    k = 2 * m
    Hx = np.empty((m, 2, 3))
    Hm = np.empty((m, 2, 2))
    cols = np.empty(m, np.int64)
    innovation = np.empty(k)
    # H Sigma (k x n), row by row: Sigma is exactly symmetric, so its pose and landmark rows serve as the
    # columns Sigma H^T needs, read contiguously.
    HS = np.empty((k, n))
    S = np.empty((k, k))
    fej = variant == VARIANT_FEJ
    scratch_x = np.empty((2, 3))  # the FEJ's Jacobians at the current mean, not used
    scratch_m = np.empty((2, 2))
    iterate = variant == VARIANT_IEKF
    rounds = iterations if iterate else 1
    x = mean.copy() if iterate else mean  # the linearisation point (the IEKF's iterate)
    for it in range(rounds):
        for a in range(m):
            lj = 3 + 2 * slots[a]
            cols[a] = lj
            hx = Hx[a]
            hm = Hm[a]
            if fej:
                range_bearing_into(prior_pose, first[slots[a]], min_range, hx, hm)
                expected_range, expected_bearing = range_bearing_into(
                    mean[:3], mean[lj : lj + 2], min_range, scratch_x, scratch_m
                )
            else:
                expected_range, expected_bearing = range_bearing_into(
                    x[:3], x[lj : lj + 2], min_range, hx, hm
                )
            innovation[2 * a] = readings[a, 0] - expected_range
            innovation[2 * a + 1] = wrap_angle(readings[a, 1] - expected_bearing)
            if it > 0:
                # z - h(x_i) - H_i (mean - x_i); the iterate's heading is never wrapped, so this is a plain sum
                e0 = x[0] - mean[0]
                e1 = x[1] - mean[1]
                e2 = x[2] - mean[2]
                f0 = x[lj] - mean[lj]
                f1 = x[lj + 1] - mean[lj + 1]
                for r in range(2):
                    innovation[2 * a + r] += (
                        hx[r, 0] * e0 + hx[r, 1] * e1 + hx[r, 2] * e2 + hm[r, 0] * f0 + hm[r, 1] * f1
                    )
            s0 = cov[0]
            s1 = cov[1]
            s2 = cov[2]
            l0 = cov[lj]
            l1 = cov[lj + 1]
            for r in range(2):
                out = HS[2 * a + r]
                h0 = hx[r, 0]
                h1 = hx[r, 1]
                h2 = hx[r, 2]
                g0 = hm[r, 0]
                g1 = hm[r, 1]
                for col in range(n):
                    out[col] = s0[col] * h0 + s1[col] * h1 + s2[col] * h2 + l0[col] * g0 + l1[col] * g1

        for a in range(m):
            lj = cols[a]
            for r in range(2):
                for c in range(k):
                    S[2 * a + r, c] = (
                        Hx[a, r, 0] * HS[c, 0]
                        + Hx[a, r, 1] * HS[c, 1]
                        + Hx[a, r, 2] * HS[c, 2]
                        + Hm[a, r, 0] * HS[c, lj]
                        + Hm[a, r, 1] * HS[c, lj + 1]
                    )
        for i in range(k):
            for j in range(i + 1, k):
                v = 0.5 * (S[i, j] + S[j, i])
                S[i, j] = v
                S[j, i] = v
        for a in range(m):
            for r in range(2):
                for c in range(2):
                    S[2 * a + r, 2 * a + c] += Q[r, c]
        if not _cholesky_in_place(S):
            return 0.0, NOT_PD
        if it == rounds - 1:
            break
        # A Gauss-Newton step x <- mean + Sigma H^T S^-1 r, needed only where H is evaluated (the pose and the
        # read landmarks); column idx of H Sigma is row idx of Sigma H^T.
        step = _solve_lower_upper(S, innovation)
        change = 0.0
        for e in range(3 + k):
            idx = e if e < 3 else cols[(e - 3) // 2] + (e - 3) % 2
            v = mean[idx]
            for i in range(k):
                v += HS[i, idx] * step[i]
            change = max(change, abs(v - x[idx]))
            x[idx] = v
        if change < ITERATION_TOLERANCE:
            break
    L = S
    for a in range(m):
        H_slots[offset + a] = slots[a]
        for r in range(2):
            for c in range(3):
                H_used[offset + a, r, c] = Hx[a, r, c]
            H_used[offset + a, r, 3] = Hm[a, r, 0]
            H_used[offset + a, r, 4] = Hm[a, r, 1]

    Wt = _gain_rows(HS, L, k, n)
    y = _forward_solve(L, innovation)

    for row in range(n):
        v = 0.0
        for i in range(k):
            v += Wt[i, row] * y[i]
        mean[row] += v
    mean[2] = wrap_angle(mean[2])
    _subtract_gain_rows(cov, Wt, k, n)

    if not track:
        return 0.0, OK
    logdet_S = 0.0
    for i in range(k):
        logdet_S += 2.0 * math.log(L[i, i])
    info = inv3(P)
    for a in range(m):
        info += sandwich_t(Hx[a], Q_inv)
    _symmetric_3x3(info)
    P[:, :] = inv3(info)
    return m * logdet_Q - logdet_S, OK


@njit(cache=True)
def _gain_rows(HS, L, k, n):
    """W^T = L^-1 H Sigma (k x n) in place of ``HS``, L the Cholesky factor of S: a forward substitution along
    whole contiguous rows. Returns ``HS``."""
    Wt = HS
    for i in range(k):
        wi = Wt[i]
        for p in range(i):
            lip = L[i, p]
            wp = Wt[p]
            for col in range(n):
                wi[col] -= lip * wp[col]
        lii = L[i, i]
        for col in range(n):
            wi[col] /= lii
    return Wt


@njit(cache=True)
def _subtract_gain_rows(cov, Wt, k, n):
    """Sigma -= W W^T (the EKF's covariance update), row by row.

    Four (then two) rows of W^T per sweep of Sigma's row: the same products subtracted in the same order as
    one at a time (so Sigma stays exactly symmetric), with a quarter of the loads and stores. A row whose column
    of W^T is zero (a landmark not yet seen, uncorrelated with everything) would subtract only zeros: it is
    skipped, which makes the update O(k N n) for n seen of N states instead of O(k N^2). k is even (two
    readings' rows per landmark reading)."""
    for row in range(n):
        untouched = True
        for i in range(k):
            if Wt[i, row] != 0.0:
                untouched = False
                break
        if untouched:
            continue
        r = cov[row]
        i = 0
        while i + 4 <= k:
            w0 = Wt[i, row]
            w1 = Wt[i + 1, row]
            w2 = Wt[i + 2, row]
            w3 = Wt[i + 3, row]
            a0 = Wt[i]
            a1 = Wt[i + 1]
            a2 = Wt[i + 2]
            a3 = Wt[i + 3]
            for col in range(n):
                r[col] = (((r[col] - w0 * a0[col]) - w1 * a1[col]) - w2 * a2[col]) - w3 * a3[col]
            i += 4
        if i < k:
            w0 = Wt[i, row]
            w1 = Wt[i + 1, row]
            a0 = Wt[i]
            a1 = Wt[i + 1]
            for col in range(n):
                r[col] = (r[col] - w0 * a0[col]) - w1 * a1[col]


@njit(cache=True)
def _forward_solve(L, b):
    """L^-1 b for a lower-triangular L."""
    k = b.shape[0]
    y = np.empty(k)
    for i in range(k):
        v = b[i]
        for p in range(i):
            v -= L[i, p] * y[p]
        y[i] = v / L[i, i]
    return y


@njit(cache=True)
def _solve_lower_upper(L, b):
    """(L L^T)^-1 b from the lower Cholesky factor L."""
    k = b.shape[0]
    y = _forward_solve(L, b)
    for i in range(k - 1, -1, -1):
        v = y[i]
        for p in range(i + 1, k):
            v -= L[p, i] * y[p]
        y[i] = v / L[i, i]
    return y


@njit(cache=True)
def _initialise_inverse(mean, cov, P, slot, reading, Q, track, fej, prior_pose, first):
    """Inverse-model initialisation: the landmark's mean and covariance blocks from the reading.

    Replaces the landmark's (uncorrelated, prior) block; the reading is not used again. The mean is the
    landmark's first estimate (kept in ``first``); with ``fej`` the heading column of Gr is taken from the
    pose's first estimate too, J (l - p_{k|k-1}), as FEJ's Jacobians are. Returns the change of log det Sigma
    (0.0 when not tracking).
    """
    lj = 3 + 2 * slot
    landmark, Gr, Gz = inverse_range_bearing(mean[:3], reading)
    if fej:
        Gr[0, 2] = -(landmark[1] - prior_pose[1])
        Gr[1, 2] = landmark[0] - prior_pose[0]
    first[slot, 0] = landmark[0]
    first[slot, 1] = landmark[1]
    old_logdet = logdet2(cov[lj : lj + 2, lj : lj + 2])
    T = sandwich(Gz, Q)
    cross = np.empty((2, cov.shape[1]))
    for c in range(cov.shape[1]):
        for r in range(2):
            cross[r, c] = Gr[r, 0] * cov[0, c] + Gr[r, 1] * cov[1, c] + Gr[r, 2] * cov[2, c]
    block = sandwich(Gr, cov[:3, :3].copy()) + T
    n = mean.shape[0]
    for c in range(n):
        cov[lj, c] = cross[0, c]
        cov[lj + 1, c] = cross[1, c]
        cov[c, lj] = cross[0, c]
        cov[c, lj + 1] = cross[1, c]
    cov[lj, lj] = block[0, 0]
    cov[lj + 1, lj + 1] = block[1, 1]
    off = 0.5 * (block[0, 1] + block[1, 0])
    cov[lj, lj + 1] = off
    cov[lj + 1, lj] = off
    mean[lj] = landmark[0]
    mean[lj + 1] = landmark[1]
    if not track:
        return 0.0
    info = inv3(P) + sandwich_t(Gr, inv2(T))
    _symmetric_3x3(info)
    P[:, :] = inv3(info)
    return logdet2(T) - old_logdet


@njit(cache=True)
def _put_landmark(mean, first, slot, x, y, first_x, first_y):
    lj = 3 + 2 * slot
    mean[lj] = x
    mean[lj + 1] = y
    first[slot, 0] = first_x
    first[slot, 1] = first_y


@njit(cache=True)
def _course_initialise(mean, observed, first, slot, reading, saved):
    """Course initialisation of ``slot``: its mean (and first estimate) from the reading, its prior covariance
    kept. The values replaced go to ``saved`` (4,), for ``_undo_course_initialisation``."""
    lj = 3 + 2 * slot
    saved[0] = mean[lj]
    saved[1] = mean[lj + 1]
    saved[2] = first[slot, 0]
    saved[3] = first[slot, 1]
    landmark, _, _ = inverse_range_bearing(mean[:3], reading)
    _put_landmark(mean, first, slot, landmark[0], landmark[1], landmark[0], landmark[1])
    observed[slot] = True


@njit(cache=True)
def _undo_course_initialisation(mean, observed, first, slot, saved):
    """Put back what ``_course_initialise`` replaced: the update that was to use the reading failed, and a
    failed correction leaves the state as it found it."""
    _put_landmark(mean, first, slot, saved[0], saved[1], saved[2], saved[3])
    observed[slot] = False


@njit(cache=True)
def correct(
    arrays: FilterArrays, options: FilterOptions, ids: I8Array1, readings: F8Array2, Q: F8Array2, track: bool
) -> tuple[float, int, int]:
    """Correction with readings of known landmarks (see ``_correct``)."""
    mean, cov, P, observed, prior_pose, first, _, H_used, H_slots = arrays
    _, _, _, min_range, course_init, sequential, variant, iterations = options
    return _correct(
        mean, cov, P, observed, ids, readings, Q, min_range, course_init, sequential, track, variant, iterations,
        prior_pose, first, H_used, H_slots,
    )  # fmt: skip


@njit(cache=True)
def _correct(
    mean, cov, P, observed, ids, readings, Q, min_range, course_init, sequential, track, variant, iterations,
    prior_pose, first, H_used, H_slots,
):  # fmt: skip
    """Correct with m range-bearing readings of known landmarks (ids are 0-based slots).

    ``variant``, ``iterations``, ``prior_pose`` and ``first`` choose where H is taken (see ``_update``);
    ``first`` (n, 2) receives each landmark's first estimate when it is initialised. ``H_used`` (>= m, 2, 5)
    and ``H_slots`` (>= m,) receive the Jacobians of the readings used, in the order used.
    Course initialisation: a landmark's first reading sets its mean (its prior covariance stays) and is then
    used in the update. Inverse initialisation: the first reading of a landmark initialises it from the
    inverse sensor model and is not used again (further readings of it in the same step are dropped; readings
    closer than ``min_range`` never initialise). Batch: all readings in one update (inverse initialisations
    after it, from the corrected pose); sequential: one reading at a time, relinearising between them.
    A landmark course-initialised for an update that fails (NOT_PD) is returned to what it was, so a failed
    batch correction changes nothing (a failed sequential one keeps the readings applied before it, and the
    change of log det it returns is theirs, for the caller to count).
    Returns (change of log det Sigma, status, number of readings used in updates).
    """
    m = ids.shape[0]
    n_landmarks = observed.shape[0]
    for i in range(m):
        if ids[i] < 0 or ids[i] >= n_landmarks:
            return 0.0, BAD_ID, 0
        if not (math.isfinite(readings[i, 0]) and math.isfinite(readings[i, 1])):
            return 0.0, BAD_INPUT, 0
    Q_inv = inv2(Q)
    logdet_Q = logdet2(Q)
    fej = variant == VARIANT_FEJ
    delta = 0.0
    used = 0
    saved = np.empty((m, 4))  # what each course initialisation replaced

    if sequential:
        one_slot = np.empty(1, np.int64)
        one_reading = np.empty((1, 2))
        for i in range(m):
            slot = ids[i]
            initialised = False
            if not observed[slot]:
                if course_init:
                    _course_initialise(mean, observed, first, slot, readings[i], saved[i])
                    initialised = True
                else:
                    if readings[i, 0] >= min_range:
                        delta += _initialise_inverse(
                            mean, cov, P, slot, readings[i], Q, track, fej, prior_pose, first
                        )
                        observed[slot] = True
                    continue
            one_slot[0] = slot
            one_reading[0, 0] = readings[i, 0]
            one_reading[0, 1] = readings[i, 1]
            d, status = _update(
                mean, cov, P, one_slot, one_reading, Q, Q_inv, logdet_Q, min_range, track, variant, iterations,
                prior_pose, first, H_used, H_slots, used,
            )  # fmt: skip
            if status != OK:
                if initialised:
                    _undo_course_initialisation(mean, observed, first, slot, saved[i])
                return delta, status, used
            delta += d
            used += 1
        return delta, OK, used

    use = np.zeros(m, np.bool_)
    to_initialise = np.zeros(m, np.bool_)
    course_initialised = np.zeros(m, np.bool_)
    for i in range(m):
        slot = ids[i]
        if observed[slot]:
            use[i] = True
        elif course_init:
            _course_initialise(mean, observed, first, slot, readings[i], saved[i])
            course_initialised[i] = True
            use[i] = True
        elif readings[i, 0] >= min_range:
            first_of_slot = True
            for p in range(i):
                if to_initialise[p] and ids[p] == slot:
                    first_of_slot = False
            to_initialise[i] = first_of_slot
    n_use = 0
    for i in range(m):
        if use[i]:
            n_use += 1
    slots = np.empty(n_use, np.int64)
    chosen = np.empty((n_use, 2))
    a = 0
    for i in range(m):
        if use[i]:
            slots[a] = ids[i]
            chosen[a, 0] = readings[i, 0]
            chosen[a, 1] = readings[i, 1]
            a += 1
    d, status = _update(
        mean, cov, P, slots, chosen, Q, Q_inv, logdet_Q, min_range, track, variant, iterations, prior_pose, first,
        H_used, H_slots, 0,
    )  # fmt: skip
    if status != OK:
        for i in range(m):
            if course_initialised[i]:
                _undo_course_initialisation(mean, observed, first, ids[i], saved[i])
        return 0.0, status, 0
    delta += d
    for i in range(m):
        if to_initialise[i]:
            delta += _initialise_inverse(mean, cov, P, ids[i], readings[i], Q, track, fej, prior_pose, first)
            observed[ids[i]] = True
    return delta, OK, n_use


@njit(cache=True)
def predict_correct(
    arrays: FilterArrays, options: FilterOptions, control: F8Array1, control_cov: F8Array2, ids: I8Array1,
    readings: F8Array2, Q: F8Array2,
) -> tuple[float, int, float, int, int]:  # fmt: skip
    """``predict`` with noise in control space, then ``correct``, both tracking the log det, in one call: the
    env's every step, where a call's arguments cost more than a small prediction. Returns (prediction's change
    of log det, its status, correction's change, its status, readings used); the correction is skipped unless
    the prediction is OK. The caller must not need a resync between them."""
    predicted, status = predict(arrays, options, control, control_cov, True, True)
    if status != OK:
        return predicted, status, 0.0, OK, 0
    corrected, corrected_status, used = correct(arrays, options, ids, readings, Q, True)
    return predicted, status, corrected, corrected_status, used

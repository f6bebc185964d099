"""Compiled kernels of the team filter (``team.TeamEKF``): N robots' poses and the landmarks in one state.

The state is (pose_1, ..., pose_N, landmark_1, ..., landmark_n): robot r's pose at columns 3r..3r+2, landmark
s at 3N + 2s. The kernels are ``kernels``' single-robot ones with the pose's columns as an argument, and they
keep its costs: a prediction touches one robot's three rows and columns (O(size)); a correction the k x size
block H Sigma and the rank-k update of Sigma (O(k size^2)), never a full H or selection matrix. A reading is a
pair of column blocks, the observer's pose (3) and a point (2): a landmark, or another robot's position
(``team_models.robot_range_bearing``), so one update serves both.

The exact running log det of ``kernels`` carries over with P, the robots' joint pose covariance conditioned on
the map (3N x 3N, the Schur complement of the map block): log det Sigma = log det Sigma_mm + log det P, and
- prediction of robot r: P's block row and column r multiplied by G, R added to block (r, r);
  d log det = log det P' - log det P (Sigma_mm untouched);
- correction: P^-1 <- P^-1 + sum H_pose^T Q^-1 H_pose, H_pose the reading's Jacobian in the pose columns (the
  observer's block; also the target's position for a robot-to-robot reading); d log det = sum log det Q -
  log det S (matrix determinant lemma);
- inverse initialisation by robot r: P^-1's block (r, r) grows by Gr^T T^-1 Gr, d log det = log det T -
  log det(prior block).
With one robot every operation is ``kernels``' in the same order, so ``TeamEKF(1, n)`` reproduces ``EKFSLAM(n)``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .codes import BAD_ID, BAD_INPUT, MODEL_ODOMETRY, MODEL_WHEELS, NOT_PD, OK, VARIANT_FEJ, VARIANT_IEKF
from .kernels import (
    ITERATION_TOLERANCE,
    _cholesky_in_place,
    _forward_solve,
    _gain_rows,
    _solve_lower_upper,
    _subtract_gain_rows,
    det3,
    inv2,
    inv3,
    logdet2,
    sandwich,
    sandwich_t,
)
from .models import (
    inverse_range_bearing,
    odometry_motion,
    range_bearing_into,
    velocity_motion,
    wheel_motion,
    wrap_angle,
)


@njit(cache=True)
def _symmetrise(a: np.ndarray) -> None:
    for i in range(a.shape[0]):
        for j in range(i + 1, a.shape[0]):
            m = 0.5 * (a[i, j] + a[j, i])
            a[i, j] = m
            a[j, i] = m


@njit(cache=True)
def _inverse(a: np.ndarray) -> np.ndarray:
    """Inverse of a symmetric positive definite matrix: cofactors for 3x3 (one robot, as ``kernels``), else
    L^-T L^-1 from its Cholesky factor L, in plain loops (exactly symmetric). NaN where it is not positive
    definite."""
    size = a.shape[0]
    if size == 3:
        return inv3(a)
    chol = a.copy()
    out = np.empty((size, size))
    if not _cholesky_in_place(chol):
        out[:, :] = np.nan
        return out
    inv_chol = np.zeros((size, size))  # L^-1, lower triangular, column by column
    for j in range(size):
        inv_chol[j, j] = 1.0 / chol[j, j]
        for i in range(j + 1, size):
            v = 0.0
            for p in range(j, i):
                v -= chol[i, p] * inv_chol[p, j]
            inv_chol[i, j] = v / chol[i, i]
    for i in range(size):
        for j in range(i, size):
            v = 0.0
            for p in range(j, size):
                v += inv_chol[p, i] * inv_chol[p, j]
            out[i, j] = v
            out[j, i] = v
    return out


@njit(cache=True)
def _log_det(a: np.ndarray) -> float:
    """log det of a symmetric positive definite matrix (NaN if it is not): det3 for 3x3, as ``kernels``."""
    if a.shape[0] == 3:
        d = det3(a)
        return math.log(d) if d > 0.0 else np.nan
    chol = a.copy()
    if not _cholesky_in_place(chol):
        return np.nan
    total = 0.0
    for i in range(a.shape[0]):
        total += 2.0 * math.log(chol[i, i])
    return total


@njit(cache=True)
def predict(
    mean, cov, P, robot, model, control, dt, wheel_base, noise, noise_in_control_space, track, prior_poses, fej,
    G_used,
):  # fmt: skip
    """Move robot ``robot``'s pose by the motion model; update its rows and columns of cov and, if tracking,
    of P (3N x 3N). ``prior_poses`` (N, 3) hold each pose as its last prediction left it (FEJ's first
    estimates, as ``kernels.predict``). Returns (change of log det Sigma, status)."""
    o = 3 * robot
    pose = mean[o : o + 3].copy()
    if model == MODEL_ODOMETRY:
        new_pose, G, V = odometry_motion(pose, control[0], control[1], control[2])
    elif model == MODEL_WHEELS:
        new_pose, G, V = wheel_motion(pose, control[0], control[1], control[2], wheel_base)
    else:
        new_pose, G, V = velocity_motion(pose, control[0], control[1], dt)
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
    _symmetrise(R)
    if fej:
        G[0, 2] = -(new_pose[1] - prior_poses[robot, 1])
        G[1, 2] = new_pose[0] - prior_poses[robot, 0]
    G_used[:, :] = G
    for i in range(3):
        mean[o + i] = new_pose[i]
        prior_poses[robot, i] = new_pose[i]

    pose_block = sandwich(G, cov[o : o + 3, o : o + 3].copy()) + R
    _symmetrise(pose_block)
    n = mean.shape[0]
    for c in range(n):
        if o <= c < o + 3:
            continue
        a0 = cov[o, c]
        a1 = cov[o + 1, c]
        a2 = cov[o + 2, c]
        for r in range(3):
            v = G[r, 0] * a0 + G[r, 1] * a1 + G[r, 2] * a2
            cov[o + r, c] = v
            cov[c, o + r] = v
    cov[o : o + 3, o : o + 3] = pose_block

    if not track:
        return 0.0, OK
    new_P = P.copy()
    for c in range(P.shape[0]):
        if o <= c < o + 3:
            continue
        a0 = P[o, c]
        a1 = P[o + 1, c]
        a2 = P[o + 2, c]
        for r in range(3):
            v = G[r, 0] * a0 + G[r, 1] * a1 + G[r, 2] * a2
            new_P[o + r, c] = v
            new_P[c, o + r] = v
    block = sandwich(G, P[o : o + 3, o : o + 3].copy()) + R
    _symmetrise(block)
    new_P[o : o + 3, o : o + 3] = block
    after = _log_det(new_P)
    before = _log_det(P)
    if not (math.isfinite(after) and math.isfinite(before)):
        return 0.0, NOT_PD
    P[:, :] = new_P
    return after - before, OK


@njit(cache=True)
def _update(
    mean, cov, P, n_robots, observers, target_cols, fej_targets, readings, Q, Q_inv, logdet_Q, min_range, track,
    variant, iterations, prior_poses,
):  # fmt: skip
    """One correction with m readings: reading a by robot ``observers[a]`` of the point at columns
    ``target_cols[a]``, ``target_cols[a] + 1`` (a landmark, or another robot's position when < 3N).

    ``kernels._update`` with the pose's columns per reading: Sigma <- Sigma - W W^T, W = (Sigma H^T) L^-T,
    S = L L^T, exactly symmetric and O(m size^2). EKF linearises at the mean; FEJ at the observer's
    ``prior_poses`` row and ``fej_targets[a]`` (a landmark's first estimate, or the target robot's predicted
    position); IEKF at Gauss-Newton iterates. Returns (change of log det Sigma, status).
    """
    m = observers.shape[0]
    if m == 0:
        return 0.0, OK
    n = mean.shape[0]
    k = 2 * m
    Hx = np.empty((m, 2, 3))
    Hm = np.empty((m, 2, 2))
    innovation = np.empty(k)
    HS = np.empty((k, n))
    S = np.empty((k, k))
    fej = variant == VARIANT_FEJ
    scratch_x = np.empty((2, 3))
    scratch_m = np.empty((2, 2))
    iterate = variant == VARIANT_IEKF
    rounds = iterations if iterate else 1
    x = mean.copy() if iterate else mean
    for it in range(rounds):
        for a in range(m):
            po = 3 * observers[a]
            tc = target_cols[a]
            hx = Hx[a]
            hm = Hm[a]
            if fej:
                range_bearing_into(prior_poses[observers[a]], fej_targets[a], min_range, hx, hm)
                expected_range, expected_bearing = range_bearing_into(
                    mean[po : po + 3], mean[tc : tc + 2], min_range, scratch_x, scratch_m
                )
            else:
                expected_range, expected_bearing = range_bearing_into(
                    x[po : po + 3], x[tc : tc + 2], min_range, hx, hm
                )
            innovation[2 * a] = readings[a, 0] - expected_range
            innovation[2 * a + 1] = wrap_angle(readings[a, 1] - expected_bearing)
            if it > 0:
                e0 = x[po] - mean[po]
                e1 = x[po + 1] - mean[po + 1]
                e2 = x[po + 2] - mean[po + 2]
                f0 = x[tc] - mean[tc]
                f1 = x[tc + 1] - mean[tc + 1]
                for r in range(2):
                    innovation[2 * a + r] += (
                        hx[r, 0] * e0 + hx[r, 1] * e1 + hx[r, 2] * e2 + hm[r, 0] * f0 + hm[r, 1] * f1
                    )
            s0 = cov[po]
            s1 = cov[po + 1]
            s2 = cov[po + 2]
            l0 = cov[tc]
            l1 = cov[tc + 1]
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
            po = 3 * observers[a]
            tc = target_cols[a]
            for r in range(2):
                for c in range(k):
                    S[2 * a + r, c] = (
                        Hx[a, r, 0] * HS[c, po]
                        + Hx[a, r, 1] * HS[c, po + 1]
                        + Hx[a, r, 2] * HS[c, po + 2]
                        + Hm[a, r, 0] * HS[c, tc]
                        + Hm[a, r, 1] * HS[c, tc + 1]
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
        step = _solve_lower_upper(S, innovation)
        change = 0.0
        for a in range(m):
            for e in range(5):
                idx = 3 * observers[a] + e if e < 3 else target_cols[a] + e - 3
                v = mean[idx]
                for i in range(k):
                    v += HS[i, idx] * step[i]
                change = max(change, abs(v - x[idx]))
                x[idx] = v
        if change < ITERATION_TOLERANCE:
            break
    L = S

    Wt = _gain_rows(HS, L, k, n)
    y = _forward_solve(L, innovation)

    for row in range(n):
        v = 0.0
        for i in range(k):
            v += Wt[i, row] * y[i]
        mean[row] += v
    for r in range(n_robots):
        mean[3 * r + 2] = wrap_angle(mean[3 * r + 2])
    _subtract_gain_rows(cov, Wt, k, n)

    if not track:
        return 0.0, OK
    logdet_S = 0.0
    for i in range(k):
        logdet_S += 2.0 * math.log(L[i, i])
    info = _inverse(P)
    pose_size = 3 * n_robots
    for a in range(m):
        po = 3 * observers[a]
        tc = target_cols[a]
        block = sandwich_t(Hx[a], Q_inv)
        for p in range(3):
            for q in range(3):
                info[po + p, po + q] += block[p, q]
        if tc < pose_size:  # another robot's position: its columns and the cross terms gain information too
            target = sandwich_t(Hm[a], Q_inv)
            for p in range(2):
                for q in range(2):
                    info[tc + p, tc + q] += target[p, q]
            for p in range(3):
                for q in range(2):
                    v = 0.0
                    for r in range(2):
                        for s in range(2):
                            v += Hx[a, r, p] * Q_inv[r, s] * Hm[a, s, q]
                    info[po + p, tc + q] += v
                    info[tc + q, po + p] += v
    _symmetrise(info)
    P[:, :] = _inverse(info)
    return m * logdet_Q - logdet_S, OK


@njit(cache=True)
def _initialise_inverse(mean, cov, P, n_robots, robot, slot, reading, Q, track, fej, prior_poses, first):
    """Inverse-model initialisation of landmark ``slot`` from robot ``robot``'s reading (as
    ``kernels._initialise_inverse``, the pose's columns at 3 robot). Returns the change of log det Sigma."""
    o = 3 * robot
    lj = 3 * n_robots + 2 * slot
    landmark, Gr, Gz = inverse_range_bearing(mean[o : o + 3].copy(), reading)
    if fej:
        Gr[0, 2] = -(landmark[1] - prior_poses[robot, 1])
        Gr[1, 2] = landmark[0] - prior_poses[robot, 0]
    first[slot, 0] = landmark[0]
    first[slot, 1] = landmark[1]
    old_logdet = logdet2(cov[lj : lj + 2, lj : lj + 2])
    T = sandwich(Gz, Q)
    n = mean.shape[0]
    cross = np.empty((2, n))
    for c in range(n):
        for r in range(2):
            cross[r, c] = Gr[r, 0] * cov[o, c] + Gr[r, 1] * cov[o + 1, c] + Gr[r, 2] * cov[o + 2, c]
    block = sandwich(Gr, cov[o : o + 3, o : o + 3].copy()) + T
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
    info = _inverse(P)
    gain = sandwich_t(Gr, inv2(T))
    for p in range(3):
        for q in range(3):
            info[o + p, o + q] += gain[p, q]
    _symmetrise(info)
    P[:, :] = _inverse(info)
    return logdet2(T) - old_logdet


@njit(cache=True)
def _course_initialise(mean, observed, first, n_robots, robot, slot, reading, saved):
    """Course initialisation of ``slot`` from robot ``robot``'s reading; what it replaced goes to ``saved``."""
    o = 3 * robot
    lj = 3 * n_robots + 2 * slot
    saved[0] = mean[lj]
    saved[1] = mean[lj + 1]
    saved[2] = first[slot, 0]
    saved[3] = first[slot, 1]
    landmark, _, _ = inverse_range_bearing(mean[o : o + 3].copy(), reading)
    mean[lj] = landmark[0]
    mean[lj + 1] = landmark[1]
    first[slot, 0] = landmark[0]
    first[slot, 1] = landmark[1]
    observed[slot] = True


@njit(cache=True)
def _undo_course_initialisation(mean, observed, first, n_robots, slot, saved):
    lj = 3 * n_robots + 2 * slot
    mean[lj] = saved[0]
    mean[lj + 1] = saved[1]
    first[slot, 0] = saved[2]
    first[slot, 1] = saved[3]
    observed[slot] = False


@njit(cache=True)
def _landmark_update(
    mean, cov, P, n_robots, robot, slots, readings, Q, Q_inv, logdet_Q, min_range, track, variant, iterations,
    prior_poses, first,
):  # fmt: skip
    m = slots.shape[0]
    observers = np.full(m, robot, np.int64)
    cols = np.empty(m, np.int64)
    fej_targets = np.empty((m, 2))
    for a in range(m):
        cols[a] = 3 * n_robots + 2 * slots[a]
        fej_targets[a, 0] = first[slots[a], 0]
        fej_targets[a, 1] = first[slots[a], 1]
    return _update(
        mean, cov, P, n_robots, observers, cols, fej_targets, readings, Q, Q_inv, logdet_Q, min_range, track,
        variant, iterations, prior_poses,
    )  # fmt: skip


@njit(cache=True)
def correct(
    mean, cov, P, observed, n_robots, robot, ids, readings, Q, min_range, course_init, sequential, track, variant,
    iterations, prior_poses, first,
):  # fmt: skip
    """Correct with robot ``robot``'s m range-bearing readings of known landmarks (``kernels.correct``, the
    same initialisation rules, batch and sequential modes, and failure handling).
    Returns (change of log det Sigma, status, number of readings used in updates)."""
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
    saved = np.empty((m, 4))

    if sequential:
        one_slot = np.empty(1, np.int64)
        one_reading = np.empty((1, 2))
        for i in range(m):
            slot = ids[i]
            initialised = False
            if not observed[slot]:
                if course_init:
                    _course_initialise(mean, observed, first, n_robots, robot, slot, readings[i], saved[i])
                    initialised = True
                else:
                    if readings[i, 0] >= min_range:
                        delta += _initialise_inverse(
                            mean,
                            cov,
                            P,
                            n_robots,
                            robot,
                            slot,
                            readings[i],
                            Q,
                            track,
                            fej,
                            prior_poses,
                            first,
                        )
                        observed[slot] = True
                    continue
            one_slot[0] = slot
            one_reading[0, 0] = readings[i, 0]
            one_reading[0, 1] = readings[i, 1]
            d, status = _landmark_update(
                mean, cov, P, n_robots, robot, one_slot, one_reading, Q, Q_inv, logdet_Q, min_range, track,
                variant, iterations, prior_poses, first,
            )  # fmt: skip
            if status != OK:
                if initialised:
                    _undo_course_initialisation(mean, observed, first, n_robots, slot, saved[i])
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
            _course_initialise(mean, observed, first, n_robots, robot, slot, readings[i], saved[i])
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
    d, status = _landmark_update(
        mean, cov, P, n_robots, robot, slots, chosen, Q, Q_inv, logdet_Q, min_range, track, variant, iterations,
        prior_poses, first,
    )  # fmt: skip
    if status != OK:
        for i in range(m):
            if course_initialised[i]:
                _undo_course_initialisation(mean, observed, first, n_robots, ids[i], saved[i])
        return 0.0, status, 0
    delta += d
    for i in range(m):
        if to_initialise[i]:
            delta += _initialise_inverse(
                mean, cov, P, n_robots, robot, ids[i], readings[i], Q, track, fej, prior_poses, first
            )
            observed[ids[i]] = True
    return delta, OK, n_use


@njit(cache=True)
def correct_robots(
    mean, cov, P, n_robots, robot, targets, readings, Q, min_range, sequential, track, variant, iterations,
    prior_poses,
):  # fmt: skip
    """Correct with robot ``robot``'s m range-bearing readings of other robots' positions (``targets`` (m,)
    robot indices), batch or sequential. A failed batch changes nothing; a failed sequential one keeps the
    readings applied before it. Returns (change of log det Sigma, status, readings used)."""
    m = targets.shape[0]
    for i in range(m):
        if targets[i] < 0 or targets[i] >= n_robots or targets[i] == robot:
            return 0.0, BAD_ID, 0
        if not (math.isfinite(readings[i, 0]) and math.isfinite(readings[i, 1])):
            return 0.0, BAD_INPUT, 0
    Q_inv = inv2(Q)
    logdet_Q = logdet2(Q)
    observers = np.full(m, robot, np.int64)
    cols = 3 * targets
    fej_targets = np.empty((m, 2))
    if not sequential:
        for a in range(m):
            fej_targets[a, 0] = prior_poses[targets[a], 0]
            fej_targets[a, 1] = prior_poses[targets[a], 1]
        d, status = _update(
            mean, cov, P, n_robots, observers, cols, fej_targets, readings, Q, Q_inv, logdet_Q, min_range, track,
            variant, iterations, prior_poses,
        )  # fmt: skip
        return (d, status, m) if status == OK else (0.0, status, 0)
    delta = 0.0
    for i in range(m):
        fej_targets[i, 0] = prior_poses[targets[i], 0]
        fej_targets[i, 1] = prior_poses[targets[i], 1]
        d, status = _update(
            mean, cov, P, n_robots, observers[i : i + 1], cols[i : i + 1], fej_targets[i : i + 1],
            readings[i : i + 1], Q, Q_inv, logdet_Q, min_range, track, variant, iterations, prior_poses,
        )  # fmt: skip
        if status != OK:
            return delta, status, i
        delta += d
    return delta, OK, m


@njit(cache=True)
def reading_nis(mean, cov, observers, target_cols, z, Q, min_range):
    """Each reading's NIS (2 dof) from the state before its correction: reading a by robot ``observers[a]``
    of the point at ``target_cols[a]`` (a landmark's or a robot's columns), nu^T S_a^-1 nu with
    S_a = H_a Sigma H_a^T + Q over the five columns it touches."""
    m = observers.shape[0]
    out = np.empty(m)
    hx = np.empty((2, 3))
    hm = np.empty((2, 2))
    H = np.empty((2, 5))
    idx = np.empty(5, np.int64)
    for a in range(m):
        po = 3 * observers[a]
        tc = target_cols[a]
        r, bearing = range_bearing_into(mean[po : po + 3], mean[tc : tc + 2], min_range, hx, hm)
        for c in range(3):
            idx[c] = po + c
            H[0, c] = hx[0, c]
            H[1, c] = hx[1, c]
        for c in range(2):
            idx[3 + c] = tc + c
            H[0, 3 + c] = hm[0, c]
            H[1, 3 + c] = hm[1, c]
        S = Q.copy()
        for p in range(2):
            for q in range(2):
                v = 0.0
                for i in range(5):
                    for j in range(5):
                        v += H[p, i] * cov[idx[i], idx[j]] * H[q, j]
                S[p, q] += v
        v0 = z[a, 0] - r
        v1 = wrap_angle(z[a, 1] - bearing)
        s01 = 0.5 * (S[0, 1] + S[1, 0])
        out[a] = (S[1, 1] * v0 * v0 - 2.0 * s01 * v0 * v1 + S[0, 0] * v1 * v1) / (
            S[0, 0] * S[1, 1] - s01 * s01
        )
    return out

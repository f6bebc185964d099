"""Compiled data association: individual Mahalanobis gating, nearest neighbour, and joint compatibility branch
and bound (JCBC, Neira & Tardos, "Data association in stochastic mapping using the joint compatibility test",
IEEE T-RA 17(6), 2001).

Why compiled: the env associates every step, and JCBC's search touches each hypothesis node with a few 2x2
operations; in Python that would cost more than the whole filter step.

For a reading z and an initialised landmark j the innovation is nu = z - h(mu, j) (bearing wrapped) with
S_j = H_j Sigma H_j^T + Q, H_j the (2, 5) Jacobian on the pose and the landmark's two entries; z is
individually compatible with j when nu^T S_j^-1 nu < chi2(2, gate). A hypothesis pairs several readings with
distinct landmarks; it is jointly compatible when the stacked innovation nu_H passes
nu_H^T S_H^-1 nu_H < chi2(2k, gate), S_H = H Sigma H^T + blockdiag(Q), cross terms included. JCBC searches
the hypotheses depth first, one reading per level (a landmark or none), extending the Cholesky factor of S_H
and the whitened innovation by one 2 x 2 block per level (O(k^2) a node), and keeps the hypothesis with the
most pairings (ties: the smaller joint distance), pruning a null branch that cannot beat the best so far.
"""

from __future__ import annotations

import math
from typing import TypeAlias

import numpy as np
from numba import njit

from ..kernel_types import BoolArray1, F8Array1, F8Array2, I8Array1
from .codes import BAD_INPUT, OK
from .kernels import FilterArrays, FilterOptions, correct
from .models import range_bearing, wrap_angle

METHOD_NEAREST = 1
METHOD_JCBC = 2

# How ``correct_unknown`` associates: method code, gates (K,) chi2(2k, gate_prob) for k = 1..K, the new-landmark
# threshold chi2(2, new_gate_prob), JCBC's node budget, and confirm_within (the calls a new landmark has to be
# matched again; 0: never forgotten). ``EKFSLAM`` builds it once per ``AssociationSettings``.
AssociationOptions: TypeAlias = "tuple[int, F8Array1, float, int, int]"


@njit(cache=True)
def _landmark_blocks(mean, cov, observed, Q, min_range, zhat, Hx, Hm, S_inv, logdet_S):
    """Predicted reading, Jacobians and inverse innovation covariance of every initialised landmark."""
    n = observed.shape[0]
    for j in range(n):
        if not observed[j]:
            continue
        lj = 3 + 2 * j
        z, hx, hm = range_bearing(mean[:3], mean[lj : lj + 2], min_range)
        zhat[j, 0] = z[0]
        zhat[j, 1] = z[1]
        Hx[j] = hx
        Hm[j] = hm
        S = _block_s(cov, hx, hm, lj, hx, hm, lj)
        for r in range(2):
            for c in range(2):
                S[r, c] += Q[r, c]
        d = S[0, 0] * S[1, 1] - S[0, 1] * S[1, 0]
        if not (d > 0.0 and S[0, 0] > 0.0):
            logdet_S[j] = np.inf
            continue
        S_inv[j, 0, 0] = S[1, 1] / d
        S_inv[j, 1, 1] = S[0, 0] / d
        off = -0.5 * (S[0, 1] + S[1, 0]) / d
        S_inv[j, 0, 1] = off
        S_inv[j, 1, 0] = off
        logdet_S[j] = math.log(d)


@njit(cache=True)
def _block_s(cov, hxa, hma, la, hxb, hmb, lb):
    """H_a Sigma[I_a, I_b] H_b^T (2, 2), I = (pose, landmark's two entries at la / lb)."""
    # T = Sigma[I_a, I_b] H_b^T (5, 2)
    T = np.empty((5, 2))
    for p in range(5):
        row = p if p < 3 else la + p - 3
        for c in range(2):
            v = 0.0
            for q in range(3):
                v += cov[row, q] * hxb[c, q]
            v += cov[row, lb] * hmb[c, 0] + cov[row, lb + 1] * hmb[c, 1]
            T[p, c] = v
    out = np.empty((2, 2))
    for r in range(2):
        for c in range(2):
            out[r, c] = (
                hxa[r, 0] * T[0, c] + hxa[r, 1] * T[1, c] + hxa[r, 2] * T[2, c] + hma[r, 0] * T[3, c]
                + hma[r, 1] * T[4, c]
            )  # fmt: skip
    return out


@njit(cache=True)
def associate(
    mean: F8Array1, cov: F8Array2, observed: BoolArray1, readings: F8Array2, Q: F8Array2, min_range: float,
    method: int, gates: F8Array1, max_nodes: int, slots: I8Array1, nearest_d2: F8Array1,
) -> int:  # fmt: skip
    """Associate m readings (range, bearing) with initialised landmarks.

    ``gates`` (K,) holds chi2(2k, gate) for k = 1..K (K >= m). Writes ``slots`` (m,): the landmark of each
    reading, -1 for none; ``nearest_d2`` (m,): each reading's smallest Mahalanobis distance to any initialised
    landmark (inf with none), for the caller's new-landmark test. Nearest: each reading independently takes,
    among its individually compatible landmarks, the one of largest likelihood (smallest d2 + ln det S).
    JCBC: see the module docstring; it stops after ``max_nodes`` hypothesis nodes and keeps the best found.
    Returns the number of nodes visited (0 for nearest).
    """
    m = readings.shape[0]
    n = observed.shape[0]
    zhat = np.zeros((n, 2))
    Hx = np.zeros((n, 2, 3))
    Hm = np.zeros((n, 2, 2))
    S_inv = np.zeros((n, 2, 2))
    logdet_S = np.zeros(n)
    _landmark_blocks(mean, cov, observed, Q, min_range, zhat, Hx, Hm, S_inv, logdet_S)

    # Individual compatibility: candidate lists per reading, with their innovations.
    gate1 = gates[0]
    n_cand = np.zeros(m, np.int64)
    cand = np.empty((m, max(n, 1)), np.int64)
    cand_d2 = np.empty((m, max(n, 1)))
    nu = np.empty((m, max(n, 1), 2))
    for i in range(m):
        slots[i] = -1
        best = np.inf
        for j in range(n):
            if not observed[j] or not math.isfinite(logdet_S[j]):
                continue
            v0 = readings[i, 0] - zhat[j, 0]
            v1 = wrap_angle(readings[i, 1] - zhat[j, 1])
            Si = S_inv[j]
            d2 = Si[0, 0] * v0 * v0 + 2.0 * Si[0, 1] * v0 * v1 + Si[1, 1] * v1 * v1
            best = min(best, d2)
            if d2 < gate1:
                c = n_cand[i]
                cand[i, c] = j
                cand_d2[i, c] = d2
                nu[i, c, 0] = v0
                nu[i, c, 1] = v1
                n_cand[i] = c + 1
        nearest_d2[i] = best

    if method == METHOD_NEAREST:
        for i in range(m):
            score = np.inf
            for c in range(n_cand[i]):
                j = cand[i, c]
                s = cand_d2[i, c] + logdet_S[j]
                if s < score:
                    score = s
                    slots[i] = j
        return 0

    # JCBC over the readings with at least one candidate (the others pair with nothing in any hypothesis).
    active = np.empty(m, np.int64)
    n_active = 0
    for i in range(m):
        if n_cand[i] > 0:
            active[n_active] = i
            n_active += 1
    if n_active == 0:
        return 0
    K = 2 * n_active
    L = np.zeros((K, K))  # Cholesky factor of S_H, one 2-row block per pairing
    y = np.zeros(K)  # L^-1 nu_H
    d2_at = np.zeros(n_active + 1)  # joint distance after k pairings
    pair_slot = np.empty(n_active, np.int64)
    pair_reading = np.empty(n_active, np.int64)
    choice = np.full(n_active + 1, -1, np.int64)
    added = np.zeros(n_active + 1, np.bool_)
    used = np.zeros(n, np.bool_)
    best_k = 0
    best_d2 = np.inf
    best_slots = np.full(m, -1, np.int64)
    current = np.full(m, -1, np.int64)
    k = 0
    depth = 0
    nodes = 0
    while depth >= 0:
        if depth == n_active:
            if k > best_k or (k == best_k and d2_at[k] < best_d2):
                best_k = k
                best_d2 = d2_at[k]
                best_slots[:] = current
            depth -= 1
            continue
        if added[depth]:  # undo this level's pairing before trying its next option
            k -= 1
            used[pair_slot[k]] = False
            current[pair_reading[k]] = -1
            added[depth] = False
        if nodes >= max_nodes:
            break
        i = active[depth]
        c = choice[depth] + 1
        choice[depth] = c
        remaining = n_active - depth - 1
        if c < n_cand[i]:
            j = cand[i, c]
            if used[j] or k + 1 + remaining < best_k:
                continue
            nodes += 1
            if _extend(cov, Hx, Hm, zhat, pair_slot, k, j, nu[i, c], Q, L, y, d2_at, gates):
                pair_slot[k] = j
                pair_reading[k] = i
                current[i] = j
                used[j] = True
                k += 1
                added[depth] = True
                depth += 1
                choice[depth] = -1
                added[depth] = False
        elif c == n_cand[i]:
            # The reading pairs with nothing: worth exploring only if the rest could still match the best.
            if k + remaining >= best_k:
                nodes += 1
                depth += 1
                choice[depth] = -1
                added[depth] = False
        else:
            depth -= 1
    for i in range(m):
        slots[i] = best_slots[i]
    return nodes


@njit(cache=True)
def _extend(cov, Hx, Hm, zhat, pair_slot, k, j, nu_new, Q, L, y, d2_at, gates):
    """Try adding landmark j (innovation nu_new) as pairing k: extend L, y and the joint distance if the
    hypothesis stays jointly compatible. Returns whether it does."""
    lj = 3 + 2 * j
    hx = Hx[j]
    hm = Hm[j]
    rows = 2 * k
    # c = L^-1 b, b the (2k, 2) cross block H_H Sigma H_j^T, written straight into L's new rows (transposed)
    for p in range(k):
        s = pair_slot[p]
        block = _block_s(cov, Hx[s], Hm[s], 3 + 2 * s, hx, hm, lj)
        for r in range(2):
            L[rows, 2 * p + r] = block[r, 0]
            L[rows + 1, 2 * p + r] = block[r, 1]
    for e in range(2):
        row = L[rows + e]
        for i in range(rows):
            v = row[i]
            for q in range(i):
                v -= L[i, q] * row[q]
            row[i] = v / L[i, i]
    D = _block_s(cov, hx, hm, lj, hx, hm, lj)
    for r in range(2):
        for c in range(2):
            v = D[r, c] + Q[r, c]
            for i in range(rows):
                v -= L[rows + r, i] * L[rows + c, i]
            D[r, c] = v
    if not D[0, 0] > 0.0:
        return False
    l00 = math.sqrt(D[0, 0])
    l10 = 0.5 * (D[1, 0] + D[0, 1]) / l00
    rest = D[1, 1] - l10 * l10
    if not rest > 0.0:
        return False
    l11 = math.sqrt(rest)
    w0 = nu_new[0]
    w1 = nu_new[1]
    for i in range(rows):
        w0 -= L[rows, i] * y[i]
        w1 -= L[rows + 1, i] * y[i]
    y0 = w0 / l00
    y1 = (w1 - l10 * y0) / l11
    d2 = d2_at[k] + y0 * y0 + y1 * y1
    if not d2 < gates[k]:
        return False
    L[rows, rows] = l00
    L[rows, rows + 1] = 0.0
    L[rows + 1, rows] = l10
    L[rows + 1, rows + 1] = l11
    y[rows] = y0
    y[rows + 1] = y1
    d2_at[k + 1] = d2
    return True


@njit(cache=True)
def correct_unknown(
    arrays: FilterArrays, options: FilterOptions, readings: F8Array2, Q: F8Array2, track: bool,
    association: AssociationOptions, slots: I8Array1, new: BoolArray1, forget: I8Array1,
) -> tuple[float, int, int, int]:  # fmt: skip
    """Associate (``associate``), start new landmarks, correct (``kernels.correct``) and keep the tentative
    landmarks' countdowns, in one call.

    A reading matched to nothing whose smallest Mahalanobis distance exceeds ``new_gate`` takes the next free
    slot (none left: dropped). Writes ``slots`` (m,) (-1: discarded), ``new`` (m,) and, in ``forget``, the
    tentative slots whose countdown ran out (the caller resets them). ``tentative`` (n,) counts the calls a
    new landmark has left to be matched again; ``confirm_within`` > 0 starts it for this call's new ones.
    Returns (change of log det Sigma, status, readings used in the update, number of slots to forget).
    """
    mean, cov, _, observed, _, _, _, _, _, tentative = arrays
    min_range = options[3]
    method, gates, new_gate, max_nodes, confirm_within = association
    m = readings.shape[0]
    n = observed.shape[0]
    for i in range(m):
        if not (math.isfinite(readings[i, 0]) and math.isfinite(readings[i, 1])):
            return 0.0, BAD_INPUT, 0, 0
    nearest = np.empty(m)
    associate(mean, cov, observed, readings, Q, min_range, method, gates, max_nodes, slots, nearest)
    free = 0
    n_use = 0
    for i in range(m):
        new[i] = False
        if slots[i] < 0 and nearest[i] > new_gate:
            while free < n and observed[free]:
                free += 1
            if free < n:
                slots[i] = free
                new[i] = True
                free += 1
        if slots[i] >= 0:
            n_use += 1
    ids = np.empty(n_use, np.int64)
    chosen = np.empty((n_use, 2))
    a = 0
    for i in range(m):
        if slots[i] >= 0:
            ids[a] = slots[i]
            chosen[a, 0] = readings[i, 0]
            chosen[a, 1] = readings[i, 1]
            a += 1
    delta, status, used = correct(arrays, options, ids, chosen, Q, track)
    if status != OK:
        return delta, status, used, 0
    for i in range(m):
        # A reading too close to initialise (inverse mode) leaves its slot free: it was not used.
        if new[i] and not observed[slots[i]]:
            slots[i] = -1
            new[i] = False
    for i in range(m):
        if slots[i] >= 0 and not new[i]:
            tentative[slots[i]] = 0
    n_forget = 0
    for j in range(n):
        if tentative[j] > 0:
            tentative[j] -= 1
            if tentative[j] == 0:
                forget[n_forget] = j
                n_forget += 1
    if confirm_within > 0:
        for i in range(m):
            if new[i]:
                tentative[slots[i]] = confirm_within
    return delta, OK, used, n_forget

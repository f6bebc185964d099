"""The env's privileged bookkeeping of unknown data association: which true landmark each filter slot holds,
and the false and missed associations of a step, in one compiled call (a dozen numpy calls otherwise).

A reading matched to a slot that holds another landmark, or clutter (true id -1) matched to any slot, is a
false association; a reading of a true landmark that was neither matched nor started a landmark is a missed
one. Starting a (tentative) landmark is not an association: the slot takes the reading's true id. A slot that
clutter started holds no landmark until a true landmark's reading is matched to it (a false association,
counted once); from then on it stands for that landmark.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..kernel_types import BoolArray1, F8Array2, I8Array1


@njit(cache=True)
def tally_associations(
    truth: I8Array1,
    z: F8Array2,
    slots: I8Array1,
    new: BoolArray1,
    forgotten: I8Array1,
    observed: BoolArray1,
    slot_truth: I8Array1,
    true_landmarks: F8Array2,
    slot_landmarks: F8Array2,
    valid: BoolArray1,
) -> tuple[int, int, I8Array1, F8Array2]:
    """Update ``slot_truth`` (n,) and ``slot_landmarks`` (n, 2) (the true position each slot holds) for the
    step's readings (true ids ``truth`` (m,), readings ``z`` (m, 2), the filter's ``slots`` (m,) and ``new``
    (m,)) and ``forgotten`` slots; write ``valid`` (n,): initialised slots that hold a true landmark.
    Returns (false associations, missed associations, slots read, their readings)."""
    for j in forgotten:
        slot_truth[j] = -1
    m = truth.shape[0]
    n_read = 0
    for i in range(m):
        if slots[i] >= 0:
            n_read += 1
    read = np.empty(n_read, np.int64)
    read_z = np.empty((n_read, 2))
    false = 0
    missed = 0
    a = 0
    for i in range(m):
        s = slots[i]
        t = truth[i]
        if s < 0:
            if t >= 0:
                missed += 1
            continue
        read[a] = s
        read_z[a, 0] = z[i, 0]
        read_z[a, 1] = z[i, 1]
        a += 1
        if new[i]:
            slot_truth[s] = t
        else:
            if t < 0 or slot_truth[s] != t:
                false += 1
            if t >= 0 and slot_truth[s] < 0:
                slot_truth[s] = t
        if t >= 0 and slot_truth[s] == t:
            slot_landmarks[s, 0] = true_landmarks[t, 0]
            slot_landmarks[s, 1] = true_landmarks[t, 1]
    for j in range(slot_truth.shape[0]):
        valid[j] = observed[j] and slot_truth[j] >= 0
    return false, missed, read, read_z

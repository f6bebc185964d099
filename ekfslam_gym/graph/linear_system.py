"""The normal equations H Δx = −b of a factor graph, assembled with a sparsity pattern computed once.

State vector: poses first (3 entries each), then landmarks (2 each). H = Σ JᵀΩJ is kept as the data array of its
upper triangle in CSC form (`SparsePattern`). The pattern follows from which variables share an edge, so it is
built at the block level (one key per pair of variables, not per scalar entry) and each edge learns, once, where
each entry of its local upper triangle lands. A linearisation is then: evaluate all edges of a kind at once, whiten
with S (SᵀS = Ω), form the local upper triangles, and sum them into H with one `np.bincount`.
"""

from __future__ import annotations

from typing import NamedTuple, Protocol

import numpy as np
from numpy.typing import NDArray

from ..angles import wrap_angles
from .factors import FACTOR_KINDS, FactorKind
from .sparse_solve import SparsePattern

__all__ = ["NormalEquations"]

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]


class _FactorSource(Protocol):
    def factors(self, kind: str) -> object: ...


class _Block(NamedTuple):
    kind: FactorKind
    index: IntArray  # (d, E) state-vector index of every Jacobian column; rows 0-2 are the first pose
    measured: Array  # (m, E)
    sqrt_info: Array  # (m, m, E)
    upper: tuple[IntArray, IntArray]  # local upper-triangle entries (a ≤ b) of the d×d edge Hessian
    dest: IntArray  # (n_upper, E) position of each local entry in the data array of H


def sqrt_information(information: Array) -> Array:
    """S with SᵀS = Ω per edge, component-first (m, m, E); Ω may be semi-definite but not indefinite.

    S = Lᵀ from a Cholesky factorisation written out over the m ≤ 3 components (vectorised over edges, far
    cheaper than a batched LAPACK call per 2×2 or 3×3 matrix); semi-definite Ω falls back to an eigendecomposition.
    """
    omega = np.ascontiguousarray(np.asarray(information, dtype=float).transpose(1, 2, 0))
    m = omega.shape[0]
    L = np.zeros_like(omega)
    with np.errstate(invalid="ignore", divide="ignore"):
        for j in range(m):
            pivot = omega[j, j] - np.sum(L[j, :j] ** 2, axis=0)
            L[j, j] = np.sqrt(pivot)
            for i in range(j + 1, m):
                L[i, j] = (omega[i, j] - np.sum(L[i, :j] * L[j, :j], axis=0)) / L[j, j]
    if np.all(np.isfinite(L)) and np.all(np.diagonal(L) > 0):
        return np.ascontiguousarray(L.transpose(1, 0, 2))
    w, U = np.linalg.eigh(information)
    scale = np.maximum(np.abs(w).max(axis=1, keepdims=True), 1e-300)
    negative = w < -1e-9 * scale
    if np.any(negative):
        bad = int(np.argmax(negative.any(axis=1)))
        raise ValueError(
            f"information matrix of edge {bad} is not positive semi-definite: {information[bad]}"
        )
    S = np.sqrt(np.clip(w, 0.0, None))[:, :, None] * np.swapaxes(U, 1, 2)
    return np.ascontiguousarray(S.transpose(1, 2, 0))


def _check_range(kind: str, what: str, idx: IntArray, size: int) -> None:
    if len(idx) and (idx.min() < 0 or idx.max() >= size):
        bad = idx[(idx < 0) | (idx >= size)][0]
        raise ValueError(f"{kind} edge refers to {what} {bad}, but there are {size} {what}s")


class NormalEquations:
    """H (upper-triangle CSC data for `pattern`) and b = Σ JᵀΩe of a graph, for any state vector.

    Built once per graph and problem size: validates indices, whitens the information matrices and maps every
    per-edge Hessian entry to its place in H. `diagonal[k]` is the position of H[k, k] in the data array.
    """

    def __init__(self, graph: _FactorSource, num_poses: int, num_landmarks: int) -> None:
        if num_poses <= 0:
            raise ValueError("the graph needs at least one pose")
        P, L = num_poses, num_landmarks
        self.num_poses, self.num_landmarks = P, L
        self.n = 3 * P + 2 * L
        nv = P + L  # variables: poses 0…P−1, then landmarks P…P+L−1
        var_dim = np.where(np.arange(nv) < P, 3, 2)
        var_off = np.concatenate([[0], np.cumsum(var_dim)[:-1]])

        # Edges as (kind, first variable, second variable or None).
        edges = []
        for name, spec in FACTOR_KINDS.items():
            f = graph.factors(name)
            if len(f) == 0:  # type: ignore[arg-type]
                continue
            first, second = f.first, f.second  # type: ignore[attr-defined]
            _check_range(name, "pose", first, P)
            if spec.second == "pose":
                _check_range(name, "pose", second, P)
                if np.any(first == second):
                    raise ValueError(f"{name} edge from pose {first[first == second][0]} to itself")
                v1 = second
            elif spec.second == "landmark":
                _check_range(name, "landmark", second, L)
                v1 = P + second
            else:
                v1 = None
            edges.append((spec, f, first, v1))

        # Block pattern: one key B·nv + A per pair of variables A ≤ B sharing an edge, plus every diagonal block.
        diag_keys = np.arange(nv, dtype=np.int64) * (nv + 1)
        off_keys = [np.maximum(v0, v1) * nv + np.minimum(v0, v1) for _, _, v0, v1 in edges if v1 is not None]
        keys = np.concatenate(off_keys + [diag_keys])
        pairs, pair_of_key = np.unique(keys, return_inverse=True)
        A, B = pairs % nv, pairs // nv
        # In column group B the row blocks A come in increasing order, the diagonal block last; row_offset is where
        # block A starts inside every column of B.
        dims_a = var_dim[A]
        exclusive = np.cumsum(dims_a) - dims_a
        group_first = np.flatnonzero(np.r_[True, B[1:] != B[:-1]])
        row_offset = exclusive - np.repeat(exclusive[group_first], np.diff(np.r_[group_first, len(B)]))
        diag_pair = pair_of_key[len(keys) - nv :]

        col_var = np.repeat(np.arange(nv), var_dim)
        col_comp = np.arange(self.n) - var_off[col_var]
        col_nnz = row_offset[diag_pair][col_var] + col_comp + 1
        indptr = np.zeros(self.n + 1, dtype=np.int64)
        np.cumsum(col_nnz, out=indptr[1:])
        indices = np.empty(indptr[-1], dtype=np.int64)
        for a in range(3):
            for b in range(3):
                sel = (a < dims_a) & (b < var_dim[B]) & ((A != B) | (a <= b))
                indices[indptr[var_off[B[sel]] + b] + row_offset[sel] + a] = var_off[A[sel]] + a
        self.pattern = SparsePattern(self.n, indptr, indices)
        self.diagonal = indptr[1:] - 1  # the diagonal entry ends each column of the upper triangle

        # Per edge: where each local upper-triangle entry lands.
        self.blocks: list[_Block] = []
        start = 0
        for spec, f, v0, v1 in edges:
            slots = [v0] if v1 is None else [v0, v1]
            slot_of, comp_of = [], []
            for s in range(len(slots)):
                d = 3 if s == 0 or spec.second == "pose" else 2
                slot_of += [s] * d
                comp_of += list(range(d))
            index = np.stack([var_off[slots[s]] + c for s, c in zip(slot_of, comp_of, strict=True)])
            if v1 is not None:
                edge_pair = pair_of_key[start : start + len(v0)]
                start += len(v0)
            ia, ib = np.triu_indices(len(slot_of))
            dest = np.empty((len(ia), len(v0)), dtype=np.int64)
            for k, (a, b) in enumerate(zip(ia, ib, strict=True)):
                sa, sb, ca, cb = slot_of[a], slot_of[b], comp_of[a], comp_of[b]
                if sa == sb:
                    v = slots[sa]
                    dest[k] = indptr[var_off[v] + cb] + row_offset[diag_pair[v]] + ca
                else:  # a in the first slot, b in the second: the block lies above or below the diagonal
                    above = v0 < v1
                    column = np.where(above, var_off[v1] + cb, var_off[v0] + ca)
                    dest[k] = indptr[column] + row_offset[edge_pair] + np.where(above, ca, cb)
            self.blocks.append(
                _Block(
                    spec,
                    index,
                    np.ascontiguousarray(f.measured.T),
                    sqrt_information(f.information),
                    (ia, ib),
                    dest,
                )
            )
        self._dest = np.concatenate([blk.dest.ravel() for blk in self.blocks]) if self.blocks else None
        self._grad_index = np.concatenate([blk.index.ravel() for blk in self.blocks]) if self.blocks else None
        # Work buffers: per block, views into one array of all local Hessian entries and one of all gradient
        # entries (in the order of _dest and _grad_index), the whitened Jacobian and a scratch row block.
        self._h_parts = np.empty(len(self._dest) if self.blocks else 0)
        self._g_parts = np.empty(len(self._grad_index) if self.blocks else 0)
        self._work = []
        h_at = g_at = 0
        for blk in self.blocks:
            d, E = blk.index.shape
            n_up = len(blk.upper[0])
            h_out = self._h_parts[h_at : h_at + n_up * E].reshape(n_up, E)
            g_out = self._g_parts[g_at : g_at + d * E].reshape(d, E)
            h_at, g_at = h_at + n_up * E, g_at + d * E
            self._work.append((h_out, g_out, np.empty((blk.kind.dim, d, E)), np.empty((d, E))))

    @staticmethod
    def _gather(x: Array, block: _Block) -> tuple[Array, ...]:
        first = x[block.index[:3]]
        if block.kind.second is None:
            return (first,)
        return first, x[block.index[3:]]

    def error(self, x: Array) -> float:
        """F(x) = Σ eᵀΩe = Σ |S e|²."""
        total = 0.0
        for block in self.blocks:
            e = block.kind.error(*self._gather(x, block), block.measured)
            w = np.einsum("ijE,jE->iE", block.sqrt_info, e)
            total += float(np.einsum("iE,iE->", w, w))
        return total

    def linearize(self, x: Array) -> tuple[Array, Array, float]:
        """(H data for `pattern`, b, F) at x."""
        nnz = self.pattern.nnz
        if not self.blocks:
            return np.zeros(nnz), np.zeros(self.n), 0.0
        total = 0.0
        for block, (h_out, g_out, wj, tmp) in zip(self.blocks, self._work, strict=True):
            e, J = block.kind.linearize(*self._gather(x, block), block.measured)
            S = block.sqrt_info
            m = len(S)
            # Row by row over the few components, vectorised over edges, into buffers reused every iteration:
            # fresh multi-megabyte temporaries cost more in page faults than the arithmetic here.
            we = np.einsum("ijE,jE->iE", S, e)  # whitened error S e, (m, E)
            for i in range(m):  # whitened Jacobian S J, (m, d, E)
                np.multiply(S[i, 0], J[0], out=wj[i])
                for k in range(1, m):
                    np.multiply(S[i, k], J[k], out=tmp)
                    wj[i] += tmp
            ia, ib = block.upper
            for row, (a, b) in enumerate(zip(ia, ib, strict=True)):  # local upper triangle of (SJ)ᵀ(SJ)
                out = h_out[row]
                np.multiply(wj[0, a], wj[0, b], out=out)
                for i in range(1, m):
                    np.multiply(wj[i, a], wj[i, b], out=tmp[0])
                    out += tmp[0]
            np.multiply(wj[0], we[0], out=g_out)  # (SJ)ᵀ(S e)
            for i in range(1, m):
                np.multiply(wj[i], we[i], out=tmp)
                g_out += tmp
            total += float(np.einsum("iE,iE->", we, we))
        hdata = np.bincount(self._dest, weights=self._h_parts, minlength=nnz)
        b = np.bincount(self._grad_index, weights=self._g_parts, minlength=self.n)
        return hdata, b, total

    def retract(self, x: Array, dx: Array, retraction: str = "add") -> Array:
        """x ⊞ Δx, headings wrapped to (−π, π] (the errors are invariant to the wrap).

        ``"add"`` adds Δx (the course's update). ``"exp"`` moves each pose along SE(2)'s exponential map, as
        GTSAM's Pose2 retract does: X ⊕ Exp(ξ) with ξ the step in the pose's own frame, ξ = (R_θᵀΔt, Δθ). Both have
        the same linearisation, so the Gauss-Newton step Δx is the same; they differ where the step turns a pose,
        the exponential map carrying its position along an arc, t ← t + V(Δθ) Δt with V(ω) = [[sin ω, cos ω − 1],
        [1 − cos ω, sin ω]] / ω (which commutes with R_θ). On long drives whose dead-reckoning start is far off
        (Victoria Park), the arcs keep the large first steps from overshooting.
        """
        out = x + dx
        headings = slice(2, 3 * self.num_poses, 3)
        if retraction == "exp":
            w = dx[headings]
            small = np.abs(w) < 1e-9
            safe = np.where(small, 1.0, w)
            a = np.where(small, 1.0 - w * w / 6.0, np.sin(safe) / safe)  # sin ω / ω
            b = np.where(small, w / 2.0, (1.0 - np.cos(safe)) / safe)  # (1 − cos ω) / ω
            tx, ty = dx[0 : 3 * self.num_poses : 3], dx[1 : 3 * self.num_poses : 3]
            out[0 : 3 * self.num_poses : 3] = x[0 : 3 * self.num_poses : 3] + a * tx - b * ty
            out[1 : 3 * self.num_poses : 3] = x[1 : 3 * self.num_poses : 3] + b * tx + a * ty
        elif retraction != "add":
            raise ValueError(f"unknown retraction {retraction!r}; expected 'add' or 'exp'")
        out[headings] = wrap_angles(out[headings])
        return out

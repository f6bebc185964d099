"""Sparse symmetric positive-definite solves with a fill-reducing ordering, for a pattern fixed across iterations.

A least-squares Hessian keeps its sparsity pattern from one Gauss-Newton iteration to the next, so the ordering and
symbolic analysis are done once (`make_solver`) and each iteration only refactors numerically (`factorize`).

Backends, in the order ``"auto"`` tries them (fastest first as measured by bench/graph.py on intel, dlr and a
1000-pose bearing-range graph, one thread):

- ``"qdldl"``: QDLDL's LDLᵀ with AMD ordering; the symbolic factorisation is reused by ``update``. Refactoring
  intel's H took 3.3 ms.
- ``"cholmod"``: CHOLMOD through scikit-sparse (optional, ``scikit-sparse<0.5`` built against
  ``libsuitesparse-dev``), simplicial with AMD. Slower than QDLDL on these graphs through this wrapper (intel 4.7-9
  ms per refactorisation, supernodal mode slower still), so it comes second.
- ``"superlu"``: SciPy's SuperLU with ``permc_spec="MMD_AT_PLUS_A"`` (SciPy's default COLAMD ordering is several
  times slower on SLAM Hessians); it refactors from scratch each time, so it is the fallback (1.6-7× QDLDL's time
  per Gauss-Newton solve).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.linalg import splu

# Optional backends, imported here rather than on first use so that a timed optimisation does not pay for imports.
try:
    import qdldl
except ImportError:  # the `graph` extra
    qdldl = None
try:
    from sksparse import cholmod
except ImportError:  # scikit-sparse<0.5, built against libsuitesparse-dev
    cholmod = None

__all__ = [
    "BACKENDS",
    "SparsePattern",
    "SparseSolver",
    "available_backends",
    "default_backend",
    "make_solver",
]

BACKENDS = ("qdldl", "cholmod", "superlu")


@dataclass(frozen=True, eq=False)  # holds arrays
class SparsePattern:
    """Upper triangle (diagonal included) of a symmetric n×n matrix in CSC form, rows sorted in each column."""

    n: int
    indptr: NDArray[np.int64]
    indices: NDArray[np.int64]
    _full: tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]] | None = field(
        default=None, repr=False, compare=False
    )

    @property
    def nnz(self) -> int:
        return int(self.indptr[-1])

    def upper(self, data: NDArray[np.float64]) -> sp.csc_matrix:
        """The upper triangle as a CSC matrix; explicit zeros are kept so the pattern never changes."""
        return sp.csc_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))

    def full_map(self) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
        """(indptr, indices, source): CSC pattern of the whole symmetric matrix and, per entry, its upper index."""
        if self._full is None:
            cols = np.repeat(np.arange(self.n), np.diff(self.indptr))
            rows = self.indices
            src = np.arange(self.nnz)
            off = rows != cols
            all_rows = np.concatenate([rows, cols[off]])
            all_cols = np.concatenate([cols, rows[off]])
            all_src = np.concatenate([src, src[off]])
            order = np.lexsort((all_rows, all_cols))
            indptr = np.zeros(self.n + 1, dtype=np.int64)
            np.cumsum(np.bincount(all_cols, minlength=self.n), out=indptr[1:])
            object.__setattr__(self, "_full", (indptr, all_rows[order], all_src[order]))
        assert self._full is not None
        return self._full

    def full(self, data: NDArray[np.float64]) -> sp.csc_matrix:
        """The whole symmetric matrix as CSC (for backends that read both triangles or either)."""
        indptr, indices, src = self.full_map()
        return sp.csc_matrix((data[src], indices, indptr), shape=(self.n, self.n))


class SparseSolver(Protocol):
    """Factor once per iteration, then solve; the pattern is fixed at construction."""

    name: str

    def factorize(self, data: NDArray[np.float64]) -> None: ...

    def solve(self, rhs: NDArray[np.float64]) -> NDArray[np.float64]: ...


class _QdldlSolver:
    name = "qdldl"

    def __init__(self, pattern: SparsePattern) -> None:
        self._qdldl = qdldl
        self._matrix = pattern.upper(np.zeros(pattern.nnz))  # built and validated once; only .data changes
        self._solver = None

    def factorize(self, data: NDArray[np.float64]) -> None:
        self._matrix.data[:] = data
        try:
            if self._solver is None:
                # The constructor runs AMD and the elimination tree once; update() reuses both.
                self._solver = self._qdldl.Solver(self._matrix, upper=True)
            else:
                self._solver.update(self._matrix, upper=True)
        except RuntimeError as exc:  # QDLDL reports a zero pivot this way
            raise np.linalg.LinAlgError(
                f"sparse LDLᵀ failed (H singular or not positive definite): {exc}"
            ) from None

    def solve(self, rhs: NDArray[np.float64]) -> NDArray[np.float64]:
        assert self._solver is not None, "factorize() first"
        return np.asarray(self._solver.solve(rhs))


class _SuperLUSolver:
    name = "superlu"

    def __init__(self, pattern: SparsePattern) -> None:
        self._pattern = pattern
        self._lu = None

    def factorize(self, data: NDArray[np.float64]) -> None:
        A = self._pattern.full(data)
        # Symmetric mode with no pivoting keeps the minimum-degree ordering of AᵀA + A intact for an SPD matrix.
        try:
            self._lu = splu(
                A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True}
            )
        except RuntimeError as exc:  # "Factor is exactly singular"
            raise np.linalg.LinAlgError(f"SuperLU failed (H singular): {exc}") from None

    def solve(self, rhs: NDArray[np.float64]) -> NDArray[np.float64]:
        assert self._lu is not None, "factorize() first"
        return self._lu.solve(np.asarray(rhs, dtype=float))


class _CholmodSolver:
    name = "cholmod"

    def __init__(self, pattern: SparsePattern) -> None:
        self._cholmod = cholmod
        self._pattern = pattern
        self._factor = None

    def factorize(self, data: NDArray[np.float64]) -> None:
        A = self._pattern.full(data)
        if self._factor is None:
            # Fill-reducing ordering and symbolic analysis, once. scikit-sparse reads the lower triangle, hence the
            # full matrix; simplicial beat supernodal on 2-D SLAM Hessians of a few thousand variables.
            self._factor = self._cholmod.analyze(A, mode="simplicial", ordering_method="amd")
        try:
            self._factor.cholesky_inplace(A)
        except self._cholmod.CholmodError as exc:
            raise np.linalg.LinAlgError(
                f"CHOLMOD failed (H singular or not positive definite): {exc}"
            ) from None

    def solve(self, rhs: NDArray[np.float64]) -> NDArray[np.float64]:
        assert self._factor is not None, "factorize() first"
        return np.asarray(self._factor(rhs))


def available_backends() -> list[str]:
    """Backends importable here, in order of preference."""
    found = []
    if qdldl is not None:
        found.append("qdldl")
    if cholmod is not None:
        found.append("cholmod")
    found.append("superlu")
    return found


def default_backend() -> str:
    """The backend ``"auto"`` picks: the first of `available_backends`."""
    return available_backends()[0]


def make_solver(pattern: SparsePattern, backend: str = "auto") -> SparseSolver:
    """A solver for matrices with this pattern; `backend` is one of `BACKENDS` or ``"auto"``."""
    name = default_backend() if backend == "auto" else backend
    if name in ("qdldl", "cholmod") and name not in available_backends():
        raise ValueError(f"sparse backend {name!r} is not installed; available: {available_backends()}")
    if name == "qdldl":
        return _QdldlSolver(pattern)
    if name == "superlu":
        return _SuperLUSolver(pattern)
    if name == "cholmod":
        return _CholmodSolver(pattern)
    raise ValueError(f"unknown sparse backend {backend!r}; expected 'auto' or one of {BACKENDS}")

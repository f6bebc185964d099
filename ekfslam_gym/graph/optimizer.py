"""Graph-based least-squares SLAM: a factor graph of SE(2) poses and 2-D landmarks, solved sparsely.

The vocabulary follows GTSAM: a `FactorGraph` holds factors (edges) with their measurements and information
matrices Ω (inverse noise covariances); `Values` holds the variables; `gauss_newton` and `levenberg_marquardt`
minimise the course's global error

    F(x) = Σ eᵀ Ω e        (no ½ factor: GTSAM's error() is F / 2)

and return an `OptimizationResult`. Variables are indices: pose p is ``values.poses[p]`` = (x, y, θ) [m, m, rad],
landmark l is ``values.landmarks[l]`` = (x, y) [m].

Edge types (see `ekfslam_gym.graph.factors` for the error functions and Jacobians):

- between (pose-pose):   e_ij = t2v(Z_ij⁻¹ (X_i⁻¹ X_j))
- pose_landmark:         e_il = R_iᵀ (x_l − t_i) − z_il
- range_bearing:         e_il = (r̂ − r, wrap(φ̂ − φ)), z = (range, bearing) of landmark l seen from pose i
- prior (unary, pose):   e_i = t2v(Z_i⁻¹ X_i)

Each iteration linearises every edge type in one vectorised pass, adds the per-edge blocks JᵀΩJ into the upper
triangle of H through an index map computed once (the sparsity pattern never changes), and solves H Δx = −b with a
fill-reducing sparse factorisation whose symbolic analysis is reused (`ekfslam_gym.graph.sparse_solve`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .factors import FACTOR_KINDS
from .linear_system import NormalEquations
from .sparse_solve import SparseSolver, make_solver

__all__ = [
    "FACTOR_KINDS",
    "GTSAM_LM",
    "FactorGraph",
    "Factors",
    "GraphProblem",
    "OptimizationResult",
    "Values",
    "gauss_newton",
    "information_from_covariance",
    "levenberg_marquardt",
    "optimize",
]

Array = NDArray[np.float64]


def information_from_covariance(covariance: ArrayLike) -> Array:
    """Ω = Σ⁻¹ for one covariance (m, m) or a stack (E, m, m)."""
    return np.linalg.inv(np.asarray(covariance, dtype=float))


# ---------------------------------------------------------------------------------------------------------------
# Variables


@dataclass(eq=False)  # holds arrays
class Values:
    """Poses (P, 3) as (x, y, θ) and landmarks (L, 2) as (x, y); both are copied to float arrays."""

    poses: Array
    landmarks: Array = field(default_factory=lambda: np.zeros((0, 2)))

    def __post_init__(self) -> None:
        self.poses = np.array(self.poses, dtype=float).reshape(-1, 3)
        self.landmarks = np.array(self.landmarks, dtype=float).reshape(-1, 2)

    @property
    def num_poses(self) -> int:
        return len(self.poses)

    @property
    def num_landmarks(self) -> int:
        return len(self.landmarks)

    @property
    def dim(self) -> int:
        """Length of the stacked state vector: 3 per pose, then 2 per landmark."""
        return 3 * self.num_poses + 2 * self.num_landmarks

    def to_vector(self) -> Array:
        """The stacked state x = (poses…, landmarks…)."""
        return np.concatenate([self.poses.ravel(), self.landmarks.ravel()])

    @classmethod
    def from_vector(cls, x: ArrayLike, num_poses: int) -> Values:
        x = np.asarray(x, dtype=float)
        return cls(x[: 3 * num_poses].reshape(-1, 3), x[3 * num_poses :].reshape(-1, 2))

    def copy(self) -> Values:
        return Values(self.poses, self.landmarks)


# ---------------------------------------------------------------------------------------------------------------
# Factors


@dataclass(frozen=True, eq=False)  # holds arrays
class Factors:
    """All edges of one kind, stacked: variable indices (E,), measurements (E, m), information matrices (E, m, m).

    `second` indexes poses for ``between``, landmarks for ``pose_landmark``/``range_bearing``; it is empty for
    ``prior``.
    """

    kind: str
    first: NDArray[np.int64]
    second: NDArray[np.int64]
    measured: Array
    information: Array

    def __len__(self) -> int:
        return len(self.first)


def _empty_factors(kind: str) -> Factors:
    m = FACTOR_KINDS[kind].dim
    none = np.zeros(0, dtype=np.int64)
    return Factors(kind, none, none, np.zeros((0, m)), np.zeros((0, m, m)))


class FactorGraph:
    """A sum of squared, information-weighted errors over poses and landmarks.

    ``add_*`` methods take one edge or a batch (arrays with a leading edge axis); an information matrix of shape
    (m, m) is shared by every edge of the batch.
    """

    def __init__(self) -> None:
        self._chunks: dict[str, list[Factors]] = {kind: [] for kind in FACTOR_KINDS}
        self._stacked: dict[str, Factors] = {}

    # -- building ----------------------------------------------------------------------------------------------
    def add_between(self, i: ArrayLike, j: ArrayLike, measured: ArrayLike, information: ArrayLike) -> None:
        """Pose-pose edges: pose j measured from pose i as the relative pose z = (x, y, θ)."""
        self._add("between", i, j, measured, information)

    def add_pose_landmark(
        self, pose: ArrayLike, landmark: ArrayLike, measured: ArrayLike, information: ArrayLike
    ) -> None:
        """Pose-landmark edges: landmark position z = (x, y) [m] in the frame of the pose."""
        self._add("pose_landmark", pose, landmark, measured, information)

    def add_range_bearing(
        self, pose: ArrayLike, landmark: ArrayLike, measured: ArrayLike, information: ArrayLike
    ) -> None:
        """Range-bearing edges: z = (range [m], bearing [rad]) of the landmark in the pose frame."""
        self._add("range_bearing", pose, landmark, measured, information)

    def add_prior(self, pose: ArrayLike, measured: ArrayLike, information: ArrayLike) -> None:
        """Unary pose priors z = (x, y, θ); with at least one, the gauge needs no other fix."""
        self._add("prior", pose, None, measured, information)

    def _add(
        self,
        kind: str,
        first: ArrayLike,
        second: ArrayLike | None,
        measured: ArrayLike,
        information: ArrayLike,
    ) -> None:
        m = FACTOR_KINDS[kind].dim
        first_idx = np.atleast_1d(np.asarray(first, dtype=np.int64)).ravel()
        n = len(first_idx)
        if second is None:
            second_idx = np.zeros(0, dtype=np.int64)
        else:
            second_idx = np.atleast_1d(np.asarray(second, dtype=np.int64)).ravel()
            if len(second_idx) != n:
                raise ValueError(f"{kind}: {n} first indices but {len(second_idx)} second indices")
        z = np.array(measured, dtype=float).reshape(-1, m)
        if len(z) != n:
            raise ValueError(f"{kind}: {n} edges but {len(z)} measurements of size {m}")
        info = np.asarray(information, dtype=float)
        if info.shape == (m, m):
            info = np.broadcast_to(info, (n, m, m))
        if info.shape != (n, m, m):
            raise ValueError(
                f"{kind}: information must have shape ({m}, {m}) or ({n}, {m}, {m}), got {info.shape}"
            )
        self._chunks[kind].append(Factors(kind, first_idx, second_idx, z, np.array(info)))
        self._stacked.pop(kind, None)

    # -- reading -----------------------------------------------------------------------------------------------
    def factors(self, kind: str) -> Factors:
        """The edges of one kind (one of `FACTOR_KINDS`), stacked."""
        if kind not in FACTOR_KINDS:
            raise KeyError(f"unknown factor kind {kind!r}; expected one of {tuple(FACTOR_KINDS)}")
        if kind not in self._stacked:
            chunks = self._chunks[kind]
            if not chunks:
                stacked = _empty_factors(kind)
            elif len(chunks) == 1:
                stacked = chunks[0]
            else:
                stacked = Factors(
                    kind,
                    np.concatenate([c.first for c in chunks]),
                    np.concatenate([c.second for c in chunks]),
                    np.concatenate([c.measured for c in chunks]),
                    np.concatenate([c.information for c in chunks]),
                )
                self._chunks[kind] = [stacked]
            self._stacked[kind] = stacked
        return self._stacked[kind]

    @property
    def between(self) -> Factors:
        return self.factors("between")

    @property
    def pose_landmark(self) -> Factors:
        return self.factors("pose_landmark")

    @property
    def range_bearing(self) -> Factors:
        return self.factors("range_bearing")

    @property
    def prior(self) -> Factors:
        return self.factors("prior")

    def __len__(self) -> int:
        return sum(len(self.factors(kind)) for kind in FACTOR_KINDS)

    def errors(self, values: Values) -> dict[str, Array]:
        """Per-edge errors e, shape (E, m), for each kind (angles wrapped)."""
        out = {}
        for kind, spec in FACTOR_KINDS.items():
            f = self.factors(kind)
            a, b = _variables(values, f)
            out[kind] = spec.error(*((a, b) if b is not None else (a,)), f.measured.T).T
        return out

    def error(self, values: Values) -> float:
        """The global error F = Σ eᵀ Ω e (twice GTSAM's `error`)."""
        total = 0.0
        for kind, e in self.errors(values).items():
            total += float(np.einsum("ei,eij,ej->", e, self.factors(kind).information, e))
        return total


def _variables(values: Values, f: Factors) -> tuple[Array, Array | None]:
    """Component-first stacks of each edge's first and second variable."""
    first = values.poses[f.first].T
    second_kind = FACTOR_KINDS[f.kind].second
    if second_kind is None:
        return first, None
    table = values.poses if second_kind == "pose" else values.landmarks
    return first, table[f.second].T


@dataclass(eq=False)  # holds arrays
class GraphProblem:
    """A graph with its initial guess and the ids its vertices had in the file it was read from.

    ``pose_ids[p]`` is the file id of pose p, ``landmark_ids[l]`` that of landmark l.
    """

    graph: FactorGraph
    initial: Values
    pose_ids: NDArray[np.int64]
    landmark_ids: NDArray[np.int64]


# ---------------------------------------------------------------------------------------------------------------
# Optimisers


@dataclass(eq=False)  # holds arrays
class OptimizationResult:
    """Outcome of an optimisation.

    `errors[0]` is the initial error and `errors[k]` the error after iteration k, so ``len(errors) ==
    iterations + 1``. `seconds` is wall time of the whole optimisation, set-up included.
    """

    values: Values
    errors: list[float]
    iterations: int
    converged: bool
    seconds: float
    method: str
    backend: str
    linear_solves: int
    diverged: bool = False  # Gauss-Newton only: the error ended above where it started (see `gauss_newton`)

    @property
    def initial_error(self) -> float:
        return self.errors[0]

    @property
    def final_error(self) -> float:
        return self.errors[-1]


IterationCallback = Callable[[int, float, Array], None]

# GTSAM's LevenbergMarquardtParams defaults (GTSAM 4.2-4.3) with its Pose2 retraction, as keyword arguments of
# `levenberg_marquardt`: λ₀ 1e-5, D = I, λ divided or multiplied by 10, a step kept when its gain ratio exceeds
# 1e-3, stop when the error changes by less than 1e-5 of itself. On Victoria Park (docs/real-data-victoria-park.md)
# these reach GTSAM's optimum where the course's settings (Marquardt's scaling, Nielsen's rule, x + Δx) end in
# poorer local minima.
GTSAM_LM: dict[str, object] = {
    "lambda_initial": 1e-5,
    "damping": "identity",
    "lambda_factor": 10.0,
    "min_gain_ratio": 1e-3,
    "relative_tolerance": 1e-5,
    "retraction": "exp",
}


def _setup(
    graph: FactorGraph, initial: Values, fix_first_pose: bool | None, backend: str
) -> tuple[NormalEquations, SparseSolver, Array, NDArray[np.int64]]:
    system = NormalEquations(graph, initial.num_poses, initial.num_landmarks)
    solver = make_solver(system.pattern, backend)
    if fix_first_pose is None:
        fix_first_pose = len(graph.prior) == 0
    gauge = system.diagonal[:3] if fix_first_pose else np.zeros(0, dtype=np.int64)
    return system, solver, initial.to_vector(), gauge


def gauss_newton(
    graph: FactorGraph,
    initial: Values,
    *,
    max_iterations: int = 100,
    step_tolerance: float = 1e-4,
    fix_first_pose: bool | None = None,
    backend: str = "auto",
    retraction: str = "add",
    callback: IterationCallback | None = None,
) -> OptimizationResult:
    """Gauss-Newton with the course's rule: stop when max|Δx| < `step_tolerance` or after `max_iterations`.

    The gauge is fixed as in the course by adding I to the first pose's 3×3 block of H; `fix_first_pose=None`
    does so only when the graph has no prior factor. `retraction` is ``"add"`` (the course's x + Δx) or ``"exp"``
    (SE(2)'s exponential map, GTSAM's; see `NormalEquations.retract`). `callback(iteration, error, x)` runs
    after every step.

    Plain Gauss-Newton takes every step, so far from the optimum the error can rise for a while (on Victoria
    Park from its dead-reckoning start it goes from 1.1e8 up to 8.2e8 before it converges, where GTSAM's
    Gauss-Newton stops at its first rise). When the iterations run out without converging and the error ends
    above where it started, the result says ``diverged=True`` and its `errors` show how far;
    Levenberg-Marquardt is the remedy.
    """
    start = time.perf_counter()
    system, solver, x, gauge = _setup(graph, initial, fix_first_pose, backend)
    errors: list[float] = []
    converged = False
    iterations = 0
    for iterations in range(1, max_iterations + 1):  # noqa: B007 - the count is reported
        hdata, b, err = system.linearize(x)
        errors.append(err)
        hdata[gauge] += 1.0
        solver.factorize(hdata)
        dx = -solver.solve(b)
        if not np.all(np.isfinite(dx)):
            raise FloatingPointError(
                "Gauss-Newton step is not finite: H is singular (an unconstrained variable?)"
            )
        x = system.retract(x, dx, retraction)
        if callback is not None:
            callback(iterations, system.error(x), x)
        if np.max(np.abs(dx), initial=0.0) < step_tolerance:
            converged = True
            break
    errors.append(system.error(x))
    return OptimizationResult(
        Values.from_vector(x, initial.num_poses),
        errors,
        iterations,
        converged,
        time.perf_counter() - start,
        "gn",
        solver.name,
        iterations,
        diverged=not converged and errors[-1] > errors[0],
    )


def levenberg_marquardt(
    graph: FactorGraph,
    initial: Values,
    *,
    max_iterations: int = 100,
    step_tolerance: float = 1e-4,
    relative_tolerance: float = 0.0,
    lambda_initial: float = 1e-5,
    lambda_max: float = 1e10,
    fix_first_pose: bool | None = None,
    backend: str = "auto",
    damping: str = "marquardt",
    lambda_factor: float | None = None,
    min_gain_ratio: float = 0.0,
    retraction: str = "add",
    callback: IterationCallback | None = None,
) -> OptimizationResult:
    """Levenberg-Marquardt: solve (H + λD)Δx = −b, keep the step if it lowers the error enough, adapt λ.

    `damping` picks D: ``"marquardt"`` is Marquardt's scaling D = diag H, ``"identity"`` is D = I (GTSAM's
    default). A step is kept when its gain ratio ρ = actual / predicted decrease exceeds `min_gain_ratio` (0: any
    decrease; GTSAM's minModelFidelity is 1e-3). Then λ shrinks, by up to 3× according to ρ (Nielsen's rule) or,
    with a `lambda_factor`, by that factor (GTSAM's fixed factor 10); otherwise λ grows (2, 4, 8…, or by the
    factor) and the step is re-solved from the same linearisation (same pattern: only a numeric
    refactorisation). Stops when an accepted step has max|Δx| < `step_tolerance`, when a step, kept or not,
    changed the error by at most `relative_tolerance`·F, when λ exceeds `lambda_max` (no descent left), or after
    `max_iterations` accepted steps. Gauge and `retraction` as in `gauss_newton`; `GTSAM_LM` holds GTSAM's
    settings.
    """
    if damping not in ("marquardt", "identity"):
        raise ValueError(f"unknown damping {damping!r}; expected 'marquardt' or 'identity'")
    start = time.perf_counter()
    system, solver, x, gauge = _setup(graph, initial, fix_first_pose, backend)
    lam, nu = lambda_initial, lambda_factor or 2.0
    hdata, b, err = system.linearize(x)
    hdata[gauge] += 1.0
    errors = [err]
    converged = False
    iterations = solves = 0
    while iterations < max_iterations:
        scale = np.maximum(hdata[system.diagonal], 1e-12) if damping == "marquardt" else np.ones(system.n)
        damped = hdata.copy()
        damped[system.diagonal] += lam * scale
        solver.factorize(damped)
        dx = -solver.solve(b)
        solves += 1
        if not np.all(np.isfinite(dx)):
            raise FloatingPointError("Levenberg-Marquardt step is not finite")
        x_new = system.retract(x, dx, retraction)
        err_new = system.error(x_new)
        # From (H + λD)Δx = −b: F(x) − L(Δx) = −2bᵀΔx − ΔxᵀHΔx = −bᵀΔx + λ ΔxᵀDΔx.
        predicted = float(-b @ dx + lam * (dx * dx) @ scale)
        rho = (err - err_new) / predicted if predicted > 0 else 1.0
        if err_new < err and rho > min_gain_ratio:
            if lambda_factor is None:
                lam *= max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
                nu = 2.0
            else:
                lam /= lambda_factor
            iterations += 1
            decrease = err - err_new
            x, err = x_new, err_new
            errors.append(err)
            if callback is not None:
                callback(iterations, err, x)
            if np.max(np.abs(dx), initial=0.0) < step_tolerance or decrease <= relative_tolerance * err:
                converged = True
                break
            hdata, b, _ = system.linearize(x)
            hdata[gauge] += 1.0
        else:
            small = relative_tolerance > 0 and abs(err_new - err) <= relative_tolerance * err
            if np.max(np.abs(dx), initial=0.0) < step_tolerance or small:
                converged = True  # no descent left at the resolution we care about
                break
            lam *= nu
            if lambda_factor is None:
                nu *= 2.0
            if lam > lambda_max:
                break
    return OptimizationResult(
        Values.from_vector(x, initial.num_poses),
        errors,
        iterations,
        converged,
        time.perf_counter() - start,
        "lm",
        solver.name,
        solves,
    )


def optimize(
    graph: FactorGraph, initial: Values, method: str = "gn", **options: object
) -> OptimizationResult:
    """Dispatch to `gauss_newton` (``"gn"``) or `levenberg_marquardt` (``"lm"``)."""
    if method == "gn":
        return gauss_newton(graph, initial, **options)  # type: ignore[arg-type]
    if method == "lm":
        return levenberg_marquardt(graph, initial, **options)  # type: ignore[arg-type]
    raise ValueError(f"unknown method {method!r}; expected 'gn' or 'lm'")

"""Graph-based least-squares SLAM: SE(2) algebra, factors, the sparse linear system, sparse solvers, the
Gauss-Newton / Levenberg-Marquardt optimiser, and the smoother that turns a recorded drive into a graph.

``ekfslam-graph FILE`` optimises a ``.dat``/``.g2o`` graph or a GTSAM 2-D dataset (``.txt``/``.graph``)
(see ``ekfslam_gym.cli.graph``).
"""

from .optimizer import (
    GTSAM_LM,
    FactorGraph,
    GraphProblem,
    OptimizationResult,
    Values,
    gauss_newton,
    levenberg_marquardt,
    optimize,
)

__all__ = [
    "GTSAM_LM",
    "FactorGraph",
    "GraphProblem",
    "OptimizationResult",
    "Values",
    "gauss_newton",
    "levenberg_marquardt",
    "optimize",
]

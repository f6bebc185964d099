"""Graph back end: edge Jacobians, sparse assembly, solvers, Gauss-Newton and Levenberg-Marquardt on known truth."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from ekfslam_gym.angles import wrap_angles
from ekfslam_gym.cli.graph import main as graph_cli
from ekfslam_gym.graph import factors as F
from ekfslam_gym.graph import se2
from ekfslam_gym.graph.linear_system import NormalEquations, sqrt_information
from ekfslam_gym.graph.optimizer import FactorGraph, Values, gauss_newton, levenberg_marquardt, optimize
from ekfslam_gym.graph.sparse_solve import available_backends, make_solver

# --------------------------------------------------------------------------------------------------------------
# SE(2)


def test_wrap_angles_half_open_interval():
    """The graph's errors and headings wrap with ekfslam_gym.angles.wrap_angles: (-pi, pi], +pi stays +pi."""
    a = wrap_angles([np.pi, -np.pi, 3 * np.pi, -3 * np.pi, 0.0, 2 * np.pi + 0.1, -0.1])
    np.testing.assert_allclose(a, [np.pi, np.pi, np.pi, np.pi, 0.0, 0.1, -0.1], atol=1e-12)
    assert np.all((a > -np.pi) & (a <= np.pi))


def test_se2_compose_between_inverse_agree_with_matrices():
    rng = np.random.default_rng(1)
    a = rng.uniform(-3, 3, size=(50, 3))
    b = rng.uniform(-3, 3, size=(50, 3))
    np.testing.assert_allclose(se2.v2t(se2.compose(a, b)), se2.v2t(a) @ se2.v2t(b), atol=1e-12)
    np.testing.assert_allclose(se2.v2t(se2.between(a, b)), np.linalg.inv(se2.v2t(a)) @ se2.v2t(b), atol=1e-12)
    np.testing.assert_allclose(se2.v2t(se2.inverse(a)), np.linalg.inv(se2.v2t(a)), atol=1e-12)
    np.testing.assert_allclose(se2.t2v(se2.v2t(a))[:, :2], a[:, :2])
    np.testing.assert_allclose(wrap_angles(se2.t2v(se2.v2t(a))[:, 2] - a[:, 2]), 0.0, atol=1e-12)


def test_odometry_jacobian_matches_finite_differences():
    rng = np.random.default_rng(2)
    for u in rng.uniform([-np.pi, 0.0, -np.pi], [np.pi, 2.0, np.pi], size=(20, 3)):
        V = se2.odometry_jacobian(u)
        h = 1e-6
        num = np.empty((3, 3))
        for k in range(3):
            d = np.zeros(3)
            d[k] = h
            diff = se2.odometry_to_relative(u + d) - se2.odometry_to_relative(u - d)
            diff[2] = wrap_angles(diff[2])
            num[:, k] = diff / (2 * h)
        np.testing.assert_allclose(V, num, atol=1e-7)
        assert np.linalg.det(V) == pytest.approx(-u[1], abs=1e-12)


# --------------------------------------------------------------------------------------------------------------
# Edge Jacobians against central finite differences


def _numeric_jacobian(error, variables, measured, h=1e-6, angle_rows=()):
    """∂e/∂(variables…) by central differences, component-first like the kernels: (m, d, E)."""
    E = measured.shape[1]
    columns = []
    for v_index, v in enumerate(variables):
        for k in range(v.shape[0]):
            plus = [x.copy() for x in variables]
            minus = [x.copy() for x in variables]
            plus[v_index][k] += h
            minus[v_index][k] -= h
            diff = error(*plus, measured) - error(*minus, measured)
            for row in angle_rows:
                diff[row] = wrap_angles(diff[row])  # the error is continuous modulo 2π
            columns.append(diff / (2 * h))
    return np.stack(columns, axis=1).reshape(measured.shape[0], -1, E)


def _poses(rng, n):
    """Poses whose headings include the wrap-around points ±π."""
    p = np.stack([rng.uniform(-5, 5, n), rng.uniform(-5, 5, n), rng.uniform(-np.pi, np.pi, n)])
    p[2, :6] = [np.pi, -np.pi, np.pi - 1e-4, -np.pi + 1e-4, 1e-9, -1e-9]
    return p


CASES = {
    "between": (F.between_error, F.between_linearize, ("pose", "pose"), 3, (2,)),
    "pose_landmark": (F.pose_landmark_error, F.pose_landmark_linearize, ("pose", "landmark"), 2, ()),
    "range_bearing": (F.range_bearing_error, F.range_bearing_linearize, ("pose", "landmark"), 2, (1,)),
    "prior": (F.prior_error, F.prior_linearize, ("pose",), 3, (2,)),
}


@pytest.mark.parametrize("kind", list(CASES))
def test_edge_jacobian_matches_finite_differences(kind):
    error, linearize, variables, m, angle_rows = CASES[kind]
    rng = np.random.default_rng(3)
    n = 40
    xs = [_poses(rng, n) if v == "pose" else rng.uniform(-5, 5, size=(2, n)) for v in variables]
    z = rng.normal(size=(m, n))
    if m == 3:
        z[2] = rng.uniform(-np.pi, np.pi, n)
        z[2, :4] = [np.pi, -np.pi, np.pi - 1e-4, 0.0]
    if kind == "range_bearing":
        z[0] = np.abs(z[0]) + 1.0
        z[1, :4] = [np.pi, -np.pi, np.pi - 1e-4, 0.0]
        # Errors whose angle sits right at ±π: the landmark straight behind the measured bearing.
        xs[1][:, 10] = xs[0][:2, 10] + 2.0 * np.array(
            [np.cos(xs[0][2, 10] + z[1, 10] + np.pi - 1e-5), np.sin(xs[0][2, 10] + z[1, 10] + np.pi - 1e-5)]
        )
    e, J = linearize(*xs, z)
    np.testing.assert_allclose(e, error(*xs, z), atol=1e-12)
    for row in angle_rows:
        assert np.all((e[row] > -np.pi) & (e[row] <= np.pi))
    J_num = _numeric_jacobian(error, xs, z, angle_rows=angle_rows)
    assert J.shape == J_num.shape
    np.testing.assert_allclose(J, J_num, rtol=1e-6, atol=1e-6)


def test_between_error_is_course_formula():
    rng = np.random.default_rng(4)
    xi, xj, z = _poses(rng, 10), _poses(rng, 10), _poses(rng, 10)
    expected = se2.t2v(np.linalg.inv(se2.v2t(z.T)) @ np.linalg.inv(se2.v2t(xi.T)) @ se2.v2t(xj.T)).T
    e = F.between_error(xi, xj, z)
    np.testing.assert_allclose(e[:2], expected[:2], atol=1e-12)
    np.testing.assert_allclose(wrap_angles(e[2] - expected[2]), 0.0, atol=1e-12)  # t2v may give −π for +π


def test_range_bearing_inverse_model_round_trip():
    rng = np.random.default_rng(5)
    poses = _poses(rng, 30)
    landmarks = rng.uniform(-5, 5, size=(2, 30))
    np.testing.assert_allclose(
        F.landmark_from_range_bearing(poses, F.range_bearing(poses, landmarks)), landmarks
    )


# --------------------------------------------------------------------------------------------------------------
# Information matrices and sparse assembly


def test_sqrt_information_definite_semidefinite_and_indefinite():
    rng = np.random.default_rng(6)
    A = rng.normal(size=(20, 3, 3))
    omega = A @ np.swapaxes(A, 1, 2) + 0.1 * np.eye(3)
    S = sqrt_information(omega).transpose(2, 0, 1)
    np.testing.assert_allclose(np.swapaxes(S, 1, 2) @ S, omega, atol=1e-10)
    semi = np.array([np.diag([4.0, 0.0])])
    S = sqrt_information(semi).transpose(2, 0, 1)
    np.testing.assert_allclose(np.swapaxes(S, 1, 2) @ S, semi, atol=1e-12)
    with pytest.raises(ValueError, match="not positive semi-definite"):
        sqrt_information(np.array([np.diag([1.0, -1.0])]))


def _random_graph(rng, num_poses=12, num_landmarks=5, noise=0.0):
    """A graph of every edge kind around known truth (measurements exact when noise=0); also edges j < i."""
    truth = Values(
        np.column_stack(
            [
                rng.uniform(-5, 5, num_poses),
                rng.uniform(-5, 5, num_poses),
                rng.uniform(-np.pi, np.pi, num_poses),
            ]
        ),
        rng.uniform(-5, 5, size=(num_landmarks, 2)),
    )
    g = FactorGraph()
    i = np.arange(num_poses - 1)
    pairs = np.concatenate([np.stack([i, i + 1], 1), [[5, 1], [num_poses - 1, 0], [3, 8]]])
    z = se2.between(truth.poses[pairs[:, 0]], truth.poses[pairs[:, 1]])
    A = rng.normal(size=(len(pairs), 3, 3))
    g.add_between(
        pairs[:, 0], pairs[:, 1], z + noise * rng.normal(size=z.shape), A @ np.swapaxes(A, 1, 2) + np.eye(3)
    )
    obs_p = rng.integers(0, num_poses, 3 * num_landmarks)
    obs_l = np.tile(np.arange(num_landmarks), 3)
    local = F.pose_landmark_error(truth.poses[obs_p].T, truth.landmarks[obs_l].T, np.zeros((2, len(obs_p)))).T
    g.add_pose_landmark(obs_p, obs_l, local + noise * rng.normal(size=local.shape), np.diag([50.0, 20.0]))
    rb = F.range_bearing(truth.poses[obs_p].T, truth.landmarks[obs_l].T).T
    g.add_range_bearing(obs_p, obs_l, rb + noise * rng.normal(size=rb.shape), [[100.0, 3.0], [3.0, 400.0]])
    return g, truth


def _dense_normal_equations(graph, values):
    """H, b and F by a plain loop over edges: the reference for the vectorised assembly."""
    P = values.num_poses
    n = values.dim
    H, b, total = np.zeros((n, n)), np.zeros(n), 0.0
    for kind, spec in F.FACTOR_KINDS.items():
        f = graph.factors(kind)
        for k in range(len(f)):
            idx = list(range(3 * f.first[k], 3 * f.first[k] + 3))
            args = [values.poses[f.first[k]][:, None]]
            if spec.second == "pose":
                idx += list(range(3 * f.second[k], 3 * f.second[k] + 3))
                args.append(values.poses[f.second[k]][:, None])
            elif spec.second == "landmark":
                idx += list(range(3 * P + 2 * f.second[k], 3 * P + 2 * f.second[k] + 2))
                args.append(values.landmarks[f.second[k]][:, None])
            e, J = spec.linearize(*args, f.measured[k][:, None])
            e, J = e[:, 0], J[:, :, 0]
            omega = f.information[k]
            H[np.ix_(idx, idx)] += J.T @ omega @ J
            b[idx] += J.T @ omega @ e
            total += e @ omega @ e
    return H, b, total


def test_vectorised_assembly_matches_dense_loop():
    rng = np.random.default_rng(7)
    g, truth = _random_graph(rng, noise=0.1)
    g.add_prior([0, 4], truth.poses[[0, 4]] + 0.05, np.diag([10.0, 10.0, 30.0]))
    values = Values(
        truth.poses + rng.normal(scale=0.2, size=truth.poses.shape),
        truth.landmarks + rng.normal(scale=0.2, size=truth.landmarks.shape),
    )
    system = NormalEquations(g, values.num_poses, values.num_landmarks)
    hdata, b, total = system.linearize(values.to_vector())
    H_ref, b_ref, total_ref = _dense_normal_equations(g, values)
    H_upper = system.pattern.upper(hdata).toarray()
    np.testing.assert_allclose(H_upper, np.triu(H_ref), rtol=1e-10, atol=1e-9)
    np.testing.assert_allclose(system.pattern.full(hdata).toarray(), H_ref, rtol=1e-10, atol=1e-9)
    np.testing.assert_allclose(b, b_ref, rtol=1e-10, atol=1e-9)
    assert total == pytest.approx(total_ref, rel=1e-12)
    assert system.error(values.to_vector()) == pytest.approx(total_ref, rel=1e-12)
    assert g.error(values) == pytest.approx(total_ref, rel=1e-12)
    np.testing.assert_array_equal(
        system.diagonal, [system.pattern.indptr[k + 1] - 1 for k in range(system.n)]
    )
    assert np.all(system.pattern.indices[system.diagonal] == np.arange(system.n))


@pytest.mark.parametrize("backend", available_backends())
def test_sparse_backends_solve_spd_system(backend):
    rng = np.random.default_rng(8)
    g, truth = _random_graph(rng, noise=0.1)
    system = NormalEquations(g, truth.num_poses, truth.num_landmarks)
    hdata, b, _ = system.linearize(truth.to_vector())
    hdata[system.diagonal[:3]] += 1.0
    H = system.pattern.full(hdata).toarray()
    solver = make_solver(system.pattern, backend)
    for scale in (1.0, 2.0):  # a second numeric factorisation reuses the symbolic one
        solver.factorize(scale * hdata)
        np.testing.assert_allclose(solver.solve(b), np.linalg.solve(scale * H, b), rtol=1e-8, atol=1e-10)


def test_unknown_backend_and_bad_edges_are_rejected():
    rng = np.random.default_rng(9)
    g, truth = _random_graph(rng)
    system = NormalEquations(g, truth.num_poses, truth.num_landmarks)
    with pytest.raises(ValueError, match="unknown sparse backend"):
        make_solver(system.pattern, "umfpack")
    with pytest.raises(ValueError, match="refers to landmark 99"):
        bad = FactorGraph()
        bad.add_pose_landmark(0, 99, [1.0, 2.0], np.eye(2))
        gauss_newton(bad, truth)
    with pytest.raises(ValueError, match="to itself"):
        bad = FactorGraph()
        bad.add_between(2, 2, [0.0, 0.0, 0.0], np.eye(3))
        gauss_newton(bad, truth)
    with pytest.raises(ValueError, match="information must have shape"):
        FactorGraph().add_between([0, 1], [1, 2], np.zeros((2, 3)), np.eye(2))
    with pytest.raises(ValueError, match="expected 'gn' or 'lm'"):
        optimize(g, truth, "newton")


# --------------------------------------------------------------------------------------------------------------
# Optimisers


def test_gauss_newton_converges_to_known_truth():
    rng = np.random.default_rng(10)
    g, truth = _random_graph(rng, num_poses=30, num_landmarks=10)
    start = Values(
        truth.poses + rng.normal(scale=[0.3, 0.3, 0.2], size=truth.poses.shape),
        truth.landmarks + rng.normal(scale=0.3, size=truth.landmarks.shape),
    )
    # Exact measurements: the optimum is the truth up to the gauge, which a prior on pose 0 removes.
    g.add_prior(0, truth.poses[0], 1e6 * np.eye(3))
    result = gauss_newton(g, start)
    assert result.converged
    assert len(result.errors) == result.iterations + 1
    assert result.errors[0] > 1e3 and result.final_error < 1e-12
    np.testing.assert_allclose(result.values.poses[:, :2], truth.poses[:, :2], atol=1e-7)
    np.testing.assert_allclose(wrap_angles(result.values.poses[:, 2] - truth.poses[:, 2]), 0.0, atol=1e-7)
    np.testing.assert_allclose(result.values.landmarks, truth.landmarks, atol=1e-7)


def test_gauge_on_first_pose_without_prior():
    rng = np.random.default_rng(11)
    g, truth = _random_graph(rng, num_poses=20, num_landmarks=6)
    start = Values(truth.poses.copy(), truth.landmarks.copy())
    start.poses[1:] += rng.normal(scale=0.1, size=(19, 3))
    start.landmarks += rng.normal(scale=0.1, size=start.landmarks.shape)
    result = gauss_newton(g, start)  # no prior: the course's H[0:3, 0:3] += I holds pose 0
    assert result.converged and result.final_error < 1e-12
    np.testing.assert_allclose(result.values.poses, truth.poses, atol=1e-7)


def _in_frame_of_first(values):
    """Poses (x, y) and landmarks relative to pose 0: the solution with the gauge freedom removed."""
    origin = np.repeat(values.poses[:1], values.num_poses, axis=0)
    poses = se2.between(origin, values.poses)[:, :2]
    local = F.pose_landmark_error(
        np.repeat(values.poses[:1].T, values.num_landmarks, axis=1),
        values.landmarks.T,
        np.zeros((2, values.num_landmarks)),
    ).T
    return np.concatenate([poses, local])


def test_levenberg_marquardt_reaches_gauss_newton_optimum():
    rng = np.random.default_rng(12)
    g, truth = _random_graph(rng, num_poses=40, num_landmarks=12, noise=0.05)
    start = Values(
        truth.poses + rng.normal(scale=[0.3, 0.3, 0.3], size=truth.poses.shape),
        truth.landmarks + rng.normal(scale=0.3, size=truth.landmarks.shape),
    )
    gn = gauss_newton(g, start)
    lm = levenberg_marquardt(g, start)
    assert gn.converged and lm.converged
    assert lm.final_error == pytest.approx(gn.final_error, rel=1e-8)
    assert np.all(np.diff(lm.errors) < 0)  # LM only accepts descent steps
    # The soft gauge (I added to pose 0's block) lets the two paths end a rigid motion apart: compare the map
    # as seen from pose 0.
    np.testing.assert_allclose(_in_frame_of_first(lm.values), _in_frame_of_first(gn.values), atol=1e-5)


def test_levenberg_marquardt_survives_a_start_where_gauss_newton_overshoots():
    # A single bearing-only-like pull from far away: a full GN step can increase the error; LM must not.
    g = FactorGraph()
    g.add_prior(0, [0.0, 0.0, 0.0], 1e4 * np.eye(3))
    g.add_range_bearing(0, 0, [1.0, 0.5], np.diag([1.0, 100.0]))
    g.add_range_bearing(0, 1, [2.0, -2.5], np.diag([1.0, 100.0]))
    start = Values([[0.0, 0.0, 0.0]], [[-3.0, 0.1], [0.05, 0.02]])
    lm = levenberg_marquardt(g, start)
    assert lm.converged and lm.final_error < 1e-10
    np.testing.assert_allclose(lm.values.landmarks[0], [np.cos(0.5), np.sin(0.5)], atol=1e-6)
    np.testing.assert_allclose(lm.values.landmarks[1], 2 * np.array([np.cos(-2.5), np.sin(-2.5)]), atol=1e-6)


def test_callback_sees_every_iteration():
    rng = np.random.default_rng(13)
    g, truth = _random_graph(rng, noise=0.01)
    seen = []
    result = gauss_newton(
        g, Values(truth.poses + 0.05, truth.landmarks), callback=lambda k, e, x: seen.append(e)
    )
    assert len(seen) == result.iterations
    np.testing.assert_allclose(seen, result.errors[1:])


# --------------------------------------------------------------------------------------------------------------
# Command line


@pytest.fixture
def small_g2o(tmp_path):
    from ekfslam_gym.data.g2o import write_g2o

    full, truth = _random_graph(np.random.default_rng(14), noise=0.02)
    g = FactorGraph()  # the g2o subset stores pose-pose and pose-landmark edges only
    for f, add in ((full.between, g.add_between), (full.pose_landmark, g.add_pose_landmark)):
        add(f.first, f.second, f.measured, f.information)
    path = tmp_path / "small.g2o"
    write_g2o(path, g, Values(truth.poses + 0.05, truth.landmarks - 0.05))
    return path


@pytest.mark.parametrize("solver", ["gn", "lm"])
def test_cli_json_prints_one_object(small_g2o, capsys, solver):
    assert graph_cli([str(small_g2o), "--json", "--solver", solver]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert len(out) == 1
    summary = json.loads(out[0])
    assert set(summary) == {"initial_error", "final_error", "iterations", "seconds", "poses", "landmarks"}
    assert summary["poses"] == 12 and summary["landmarks"] == 5
    assert summary["final_error"] < summary["initial_error"]
    assert summary["seconds"] >= 0 and summary["iterations"] >= 1


def test_cli_text_and_plot(small_g2o, tmp_path, capsys):
    png = tmp_path / "plot.png"
    assert graph_cli([str(small_g2o), "--plot", str(png)]) == 0
    assert "iteration   0" in capsys.readouterr().out
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_cli_errors(tmp_path, capsys):
    bad = tmp_path / "graph.csv"
    bad.write_text("")
    for path, message in ((bad, "unknown graph format"), (tmp_path / "missing.g2o", "missing.g2o")):
        with pytest.raises(SystemExit) as exit_:
            graph_cli([str(path)])
        assert exit_.value.code == 2
        err = capsys.readouterr().err
        assert err.startswith("ekfslam-graph: error: ") and message in err and "Errno" not in err


def test_python_dash_m_entry_point(small_g2o):
    run = subprocess.run(
        [sys.executable, "-m", "ekfslam_gym.cli.graph", str(small_g2o), "--json"],
        capture_output=True,
        text=True,
        check=True,
        timeout=120,
    )
    assert json.loads(run.stdout)["poses"] == 12


@pytest.mark.parametrize("backend", available_backends())
def test_unconstrained_variable_is_reported(backend):
    # Landmark 1 has no edge at all: H has an empty 2×2 block.
    g = FactorGraph()
    g.add_pose_landmark(0, 0, [1.0, 0.0], np.eye(2))
    with pytest.raises((np.linalg.LinAlgError, FloatingPointError)):
        gauss_newton(g, Values([[0.0, 0.0, 0.0]], [[0.5, 0.0], [2.0, 2.0]]), backend=backend)

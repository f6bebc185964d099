"""The trade-off points, their Pareto front and the command line that plots them."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from ekfslam_gym.cli.tradeoff import main
from ekfslam_gym.evaluation.aggregate import aggregate
from ekfslam_gym.evaluation.report import json_safe
from ekfslam_gym.evaluation.tradeoff import Point, pareto_front, points_from_episodes, read_csv, write_csv


def _dominates(q: Point, p: Point, sx: float, sy: float) -> bool:
    at_least = sx * q.x <= sx * p.x and sy * q.y <= sy * p.y
    return at_least and (sx * q.x < sx * p.x or sy * q.y < sy * p.y)


@pytest.mark.parametrize("x, sx", [("map_log_det", 1.0), ("loop_closures", -1.0)])
@pytest.mark.parametrize("y, sy", [("landmark_rmse", 1.0), ("seen_fraction", -1.0)])
def test_the_front_is_every_point_that_no_other_point_dominates(x, sx, y, sy):
    rng = np.random.default_rng(3)
    for trial in range(30):
        n = int(rng.integers(1, 40))
        # few distinct values, so ties on one metric and repeated points are common
        xs, ys = rng.integers(0, 8, n).astype(float), rng.integers(0, 8, n).astype(float)
        points = [Point("g", f"m{i}", 10, xs[i], 0, 0, ys[i], 0, 0) for i in range(n)]
        expected = {p.name for p in points if not any(_dominates(q, p, sx, sy) for q in points)}
        front = pareto_front(points, x, y)
        assert {p.name for p in front} == expected, trial
        assert [sx * p.x for p in front] == sorted(sx * p.x for p in front)  # from x's best end


def test_the_front_leaves_out_undefined_points_and_refuses_a_metric_with_no_better_side():
    points = [Point("g", "a", 5, 1.0, 0, 2, 1.0, 0, 2), Point("g", "b", 5, math.nan, 0, 0, 0.0, 0, 0)]
    assert [p.name for p in pareto_front(points, "map_log_det", "landmark_rmse")] == ["a"]
    with pytest.raises(ValueError, match="no better side"):
        pareto_front(points, "map_log_det", "anees")


def _episodes(rng: np.random.Generator, n: int) -> list[dict[str, float]]:
    return [
        {
            "seed": 20000 + i,
            "map_log_det": float(rng.normal(-100, 50)),
            "landmark_rmse": float(rng.gamma(4, 0.03)),
        }
        for i in range(n)
    ]


def test_points_are_aggregated_as_the_evaluation_tables_are():
    rng = np.random.default_rng(0)
    episodes = {"a": _episodes(rng, 30), "b": _episodes(rng, 7)}
    episodes["b"][2]["landmark_rmse"] = math.nan  # an episode that saw nothing
    points = points_from_episodes(episodes, "map_log_det", "landmark_rmse", "runs")
    for p in points:
        table = aggregate(episodes[p.name], ("map_log_det", "landmark_rmse"))
        assert (p.group, p.episodes) == ("runs", len(episodes[p.name]))
        assert (p.x, [p.x_lo, p.x_hi]) == (table["map_log_det"]["iqm"], table["map_log_det"]["ci"])
        assert (p.y, [p.y_lo, p.y_hi]) == (table["landmark_rmse"]["iqm"], table["landmark_rmse"]["ci"])
    with pytest.raises(ValueError, match="has no 'ate'"):
        points_from_episodes(episodes, "map_log_det", "ate", "runs")


def test_the_csv_gives_back_the_points_it_was_written_from(tmp_path):
    points = [
        Point(
            "PPO, seeds 0-4",
            'run "a", best',
            70,
            np.float64(-250.38123456789),
            -297.0,
            -196.5,
            0.1041,
            0.085,
            0.132,
        ),
        Point("planners", "frontier", 70, 1e-300, -1.0, 2.0, math.nan, math.nan, math.nan),
    ]
    path = write_csv(points, tmp_path / "sub" / "points.csv", "map_log_det", "landmark_rmse")
    x, y, back = read_csv(path)
    assert (x, y) == ("map_log_det", "landmark_rmse")
    assert back[0] == points[0]
    assert back[1].x == 1e-300 and math.isnan(back[1].y)
    (tmp_path / "bad.csv").write_text("a,b\n1,2\n")
    with pytest.raises(ValueError, match="not a CSV of trade-off points"):
        read_csv(tmp_path / "bad.csv")


def test_the_command_plots_json_groups_and_redraws_them_from_its_csv(tmp_path, capsys):
    rng = np.random.default_rng(1)
    (tmp_path / "ppo.json").write_text(json.dumps({"seed0": _episodes(rng, 20), "seed1": _episodes(rng, 20)}))
    (tmp_path / "greedy.json").write_text(json.dumps({"greedy": _episodes(rng, 20)}))
    args = [str(tmp_path / "ppo.json"), str(tmp_path / "greedy.json"), "--label", "PPO"]
    assert main(args + ["--csv", str(tmp_path / "p.csv"), "--plot", str(tmp_path / "p.png"), "--ci", "greedy",
                        "--annotate", "greedy", "--x-line=-120:greedy", "--y-line", "0.1"]) == 0  # fmt: skip
    first = capsys.readouterr().out
    assert (tmp_path / "p.png").stat().st_size > 10_000
    _, _, points = read_csv(tmp_path / "p.csv")
    assert [(p.group, p.name) for p in points] == [("PPO", "seed0"), ("PPO", "seed1"), ("greedy", "greedy")]
    front = pareto_front(points, "map_log_det", "landmark_rmse")
    assert first.count("\n  ") == len(front) and all(f"/ {p.name}:" in first for p in front)
    assert main([str(tmp_path / "p.csv"), "--plot", str(tmp_path / "again.png")]) == 0
    assert capsys.readouterr().out == first


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--ci", "nobody"], "no group 'nobody'"),
        (["--label", "a", "--label", "b", "--label", "c"], "3 --label for 2 JSON files"),
        (["--y", "ate"], "has no 'ate'"),
        (["--x-line", "left:edge"], "expected VALUE or VALUE:TEXT"),
    ],
)
def test_the_command_says_what_is_wrong_with_its_input(tmp_path, capsys, extra, message):
    rng = np.random.default_rng(2)
    for name in ("a", "b"):
        (tmp_path / f"{name}.json").write_text(json.dumps({name: _episodes(rng, 5)}))
    with pytest.raises(SystemExit) as exit_info:
        main([str(tmp_path / "a.json"), str(tmp_path / "b.json"), *extra])
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err


def test_the_command_refuses_files_it_cannot_read_as_points(tmp_path, capsys):
    (tmp_path / "list.json").write_text(json.dumps([{"map_log_det": 1.0}]))
    write_csv([Point("g", "m", 3, 1.0, 0, 2, 3.0, 2, 4)], tmp_path / "ate.csv", "map_log_det", "ate")
    for path, message in [("list.json", "expected {name: [episode metrics]}"), ("ate.csv", "not map_log_det against landmark_rmse"), ("missing.json", "No such file")]:  # fmt: skip
        with pytest.raises(SystemExit):
            main([str(tmp_path / path)])
        assert message in capsys.readouterr().err


# docs/results.md's reference lines: (baseline, field, value as written), each a baseline's IQM or CI end
DOCUMENTED_LINES = {
    "Large-v0_heldout": [("frontier", "x_lo", -224.1), ("greedy", "y_lo", 0.1177)],
    "Large-v0_evaluation": [("frontier", "x_lo", -246.5), ("greedy", "y_lo", 0.1088)],
    "v0_heldout": [("greedy", "x", -558.9), ("lawnmower", "x_lo", -547.7), ("greedy", "y", 0.0513)],
    "Loop-v0_heldout": [("frontier", "x_lo", -584.0), ("greedy", "y_lo", 0.0930)],
}


@pytest.mark.parametrize("name", sorted(DOCUMENTED_LINES))
def test_the_documented_figures_redraw_from_their_csvs_with_their_baselines_lines(tmp_path, capsys, name):
    """docs/results.md redraws each figure from its committed points, with lines at the baselines' figures."""
    csv_path = Path(__file__).resolve().parents[2] / "docs" / f"tradeoff_EKFSLAM-{name}.csv"
    args = [str(csv_path), "--ci", "shipped policy", "--ci", "baselines", "--annotate", "baselines"]
    assert main(args + ["--plot", str(tmp_path / "figure.png")]) == 0
    _, _, points = read_csv(csv_path)
    baselines = {p.name: p for p in points if p.group == "baselines"}
    assert set(baselines) == {"greedy", "frontier", "lawnmower"}
    assert len([p for p in points if p.group == "shipped policy"]) == 1
    for baseline, field, value in DOCUMENTED_LINES[name]:
        assert getattr(baselines[baseline], field) == pytest.approx(
            value, abs=0.051 if abs(value) > 1 else 5e-5
        )
    front = capsys.readouterr().out
    # docs/results.md says whether the shipped policy is on each front: held out on Large, finals of its own
    # recipe (seed 1's, -382 / 0.127 m, and seed 2's, -395 / 0.133 m) beat it on both metrics
    assert ("shipped policy" in front) == (name != "Large-v0_heldout")


def test_a_metric_with_no_better_side_is_plotted_without_a_front(tmp_path, capsys):
    rng = np.random.default_rng(4)
    episodes = _episodes(rng, 8)
    for e in episodes:
        e["anees"] = float(rng.gamma(3, 1))
    (tmp_path / "a.json").write_text(json.dumps({"a": episodes}))
    assert main([str(tmp_path / "a.json"), "--y", "anees", "--plot", str(tmp_path / "a.png")]) == 0
    assert "no Pareto front" in capsys.readouterr().out
    assert (tmp_path / "a.png").is_file()


def test_what_evaluate_writes_is_read_undefined_metrics_and_all(tmp_path, capsys):
    """evaluate --episodes-json writes a NaN metric (an episode that saw no landmark) as null."""
    rng = np.random.default_rng(5)
    episodes = _episodes(rng, 9)
    episodes[4]["landmark_rmse"] = math.nan
    (tmp_path / "ppo.json").write_text(json.dumps(json_safe({"ppo": episodes})))
    assert "null" in (tmp_path / "ppo.json").read_text()
    assert main([str(tmp_path / "ppo.json"), "--csv", str(tmp_path / "p.csv")]) == 0
    capsys.readouterr()
    (point,) = read_csv(tmp_path / "p.csv")[2]
    expected = aggregate(episodes, ("landmark_rmse",))["landmark_rmse"]
    assert (point.y, [point.y_lo, point.y_hi]) == (expected["iqm"], expected["ci"])
    assert point.episodes == 9


@pytest.mark.parametrize(
    "content, message",
    [({"m": [1, 2]}, "is not a mapping of metrics"), ({}, "hold no models"), ({"m": []}, "has no episodes")],
)
def test_the_command_refuses_json_with_no_episodes_to_read(tmp_path, capsys, content, message):
    (tmp_path / "a.json").write_text(json.dumps(content))
    with pytest.raises(SystemExit):
        main([str(tmp_path / "a.json")])
    assert message in capsys.readouterr().err


def test_a_csv_is_known_by_its_suffix_in_any_case_and_labels_go_to_the_json_files(tmp_path, capsys):
    rng = np.random.default_rng(6)
    write_csv(
        [Point("old", "m", 3, 1.0, 0, 2, 3.0, 2, 4)], tmp_path / "old.CSV", "map_log_det", "landmark_rmse"
    )
    (tmp_path / "new.json").write_text(json.dumps({"n": _episodes(rng, 6)}))
    args = [str(tmp_path / "old.CSV"), str(tmp_path / "new.json"), "--label", "new runs"]
    assert main(args + ["--csv", str(tmp_path / "both.csv")]) == 0
    capsys.readouterr()
    assert [(p.group, p.name) for p in read_csv(tmp_path / "both.csv")[2]] == [
        ("old", "m"),
        ("new runs", "n"),
    ]

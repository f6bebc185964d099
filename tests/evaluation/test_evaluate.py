"""The evaluation CLI and functions: the JSON schema, comparisons, files, and reproducibility."""

from __future__ import annotations

import json
import math

import pytest
from ekfslam_gym.agents import make_agent

from ekfslam_gym.cli.common import parse_seeds
from ekfslam_gym.cli.evaluate import main
from ekfslam_gym.evaluation.aggregate import aggregate, summary
from ekfslam_gym.evaluation.episode_metrics import METRIC_KEYS
from ekfslam_gym.evaluation.report import markdown_table
from ekfslam_gym.evaluation.rollout import evaluate_agent
from ekfslam_gym.seeds import HELD_OUT_SEEDS

SHORT = ["--seeds", "0-1", "--max-episode-steps", "20", "--no-progress"]


def _check_summary(obj, agent, episodes):
    assert set(obj) == {"agent", "episodes", "metrics"}
    assert obj["agent"] == agent and obj["episodes"] == episodes
    assert list(obj["metrics"]) == list(METRIC_KEYS)
    for name, entry in obj["metrics"].items():
        assert set(entry) == {"iqm", "ci", "mean"}, name
        assert len(entry["ci"]) == 2
        for value in (entry["iqm"], entry["mean"], *entry["ci"]):
            assert value is None or isinstance(value, (int, float))
        if entry["iqm"] is not None:
            assert entry["ci"][0] <= entry["iqm"] + 1e-9 and entry["iqm"] <= entry["ci"][1] + 1e-9


def test_json_is_exactly_one_object_with_the_schema(capsys):
    assert main(["--agent", "random", "--json", *SHORT]) == 0
    out = capsys.readouterr().out
    obj = json.loads(out)  # exactly one JSON document: json.loads rejects trailing data
    _check_summary(obj, "random", 2)
    assert obj["metrics"]["path_length"]["iqm"] > 0


def test_comparison_json_is_keyed_by_agent_and_writes_table_and_plot(capsys, tmp_path):
    table, plot = tmp_path / "t.md", tmp_path / "p.png"
    argv = ["--agent", "circle,greedy", "--json", "--table", str(table), "--plot", str(plot), *SHORT]
    assert main(argv) == 0
    obj = json.loads(capsys.readouterr().out)
    assert list(obj) == ["circle", "greedy"]
    for name, entry in obj.items():
        _check_summary(entry, name, 2)
    text = table.read_text()
    assert "| circle | 2 |" in text and "| greedy | 2 |" in text and "map_log_det" in text
    assert plot.stat().st_size > 10_000


def test_text_output_and_gif(capsys, tmp_path):
    pytest.importorskip("pygame")
    assert main(["--agent", "lawnmower", "--seeds", "7", "--max-episode-steps", "6", "--gif", str(tmp_path), "--no-progress"]) == 0  # fmt: skip
    out = capsys.readouterr().out
    assert "lawnmower: 1 episodes" in out and "map_log_det" in out
    from PIL import Image

    with Image.open(tmp_path / "lawnmower_seed7.gif") as gif:
        assert gif.n_frames == 4  # reset + 6 steps = 7 frames, every 2nd kept


def test_bad_arguments_are_rejected():
    with pytest.raises(SystemExit):
        main(["--agent", "teleport", *SHORT])
    with pytest.raises(SystemExit):
        main(["--agent", "ppo", "--env-id", "EKFSLAM-v9", *SHORT])  # no --model, and no shipped policy there
    with pytest.raises(SystemExit):
        main([*SHORT])  # neither --agent nor --compare


def test_parse_seeds_and_the_held_out_suite():
    assert parse_seeds("3-6") == [3, 4, 5, 6]
    assert parse_seeds("1,4,9") == [1, 4, 9]
    assert parse_seeds("0-2,10") == [0, 1, 2, 10]
    assert HELD_OUT_SEEDS == tuple(range(10000, 10050))
    assert parse_seeds("heldout") == list(HELD_OUT_SEEDS)
    for bad in ("5-2", "a-b", ""):
        with pytest.raises(Exception):  # noqa: B017 (argparse's ArgumentTypeError)
            parse_seeds(bad)


def test_evaluate_agent_is_reproducible_and_paired():
    first = evaluate_agent(make_agent("random"), "EKFSLAM-v0", [0, 1], max_episode_steps=15)
    second = evaluate_agent(make_agent("random"), "EKFSLAM-v0", [0, 1], max_episode_steps=15)
    assert first == second
    assert [e["seed"] for e in first] == [0, 1] and all(e["steps"] == 15 for e in first)
    assert set(METRIC_KEYS) <= set(first[0])


def test_max_episode_steps_goes_into_the_env_config():
    from ekfslam_gym.evaluation.rollout import make_env

    env = make_env("EKFSLAM-Loop-v0", max_episode_steps=12)
    assert env.unwrapped.config.max_episode_steps == 12
    assert env.unwrapped.config.world.layout == "loop"  # the preset is kept
    env.close()


def test_aggregate_uses_iqm_and_skips_nans():
    episodes = [dict.fromkeys(METRIC_KEYS, float(v)) for v in (1, 2, 3, 4, 5, 6, 7, 100)]
    episodes[0]["ate"] = math.nan
    agg = aggregate(episodes)
    assert agg["return"]["iqm"] == pytest.approx(4.5)
    assert agg["return"]["mean"] == pytest.approx(128 / 8)
    assert agg["ate"]["iqm"] == pytest.approx(5.0)  # 7 finite values: trim one from each end
    assert agg["ate"]["mean"] == pytest.approx(127 / 7)
    table = markdown_table({"x": summary("x", episodes)})
    assert "| x | 8 | 4.50 [" in table


def test_episode_metrics_are_consistent_with_the_env():
    (episode,) = evaluate_agent(make_agent("lawnmower"), "EKFSLAM-v0", [3], max_episode_steps=40)
    assert episode["seen_fraction"] == pytest.approx(1 - episode["missed_landmarks"] / 30)
    assert 0 <= episode["nees_in_bounds"] <= 1 and episode["anees"] > 0
    assert episode["ate"] >= 0 and episode["landmark_rmse"] >= 0 and 0 < episode["path_length"] <= 4.0 + 1e-6
    assert episode["map_log_det"] < 30 * 2 * math.log(100.0)  # below the all-unseen prior


def test_smoother_option_reports_the_smoothed_episode_beside_the_filter(capsys):
    import json

    assert main(["--agent", "circle", "--seeds", "10000", "--smoother", "--json", "--no-progress"]) == 0
    out = json.loads(capsys.readouterr().out)
    metrics = out["metrics"]
    assert {"smoother_ate", "smoother_landmark_rmse", "ate", "landmark_rmse"} <= set(metrics)
    assert metrics["smoother_ate"]["mean"] < metrics["ate"]["mean"]


def test_env_kwargs_go_on_top_of_the_training_record_section_by_section():
    from ekfslam_gym.evaluation.rollout import merge_env_kwargs

    trained = {"filter": {"motion_model": "odometry", "pose_prior": 1e-6}, "action": {"kind": "primitives"}}
    merged = merge_env_kwargs(trained, {"filter": {"variant": "fej"}, "max_episode_steps": 30})
    assert merged == {
        "filter": {"motion_model": "odometry", "pose_prior": 1e-6, "variant": "fej"},
        "action": {"kind": "primitives"},
        "max_episode_steps": 30,
    }
    assert trained["filter"] == {"motion_model": "odometry", "pose_prior": 1e-6}  # the record is left alone
    assert merge_env_kwargs(None, None) == {}
    assert merge_env_kwargs({"filter": {"variant": "ekf"}}, {"filter": None}) == {"filter": None}


@pytest.mark.parametrize("kind", ["waypoint", "primitives"])
def test_an_agent_is_refused_in_an_interface_it_does_not_act_in(kind, capsys):
    # A velocity command is two floats in [-1, 1], as a waypoint goal is: without the check the waypoint env
    # drove the frontier agent's commands as goals and reported another agent's episode.
    env_kwargs = json.dumps({"action": {"kind": kind}})
    with pytest.raises(SystemExit) as exit_info:
        main(["--agent", "frontier", "--env-kwargs", env_kwargs, *SHORT])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert "--agent frontier: agent 'frontier' acts in action.kind 'velocity'" in err
    assert f"frontier-{kind}" in err and "lawnmower" not in err  # the agents that do act in it
    with pytest.raises(ValueError, match=f"this env takes '{kind}' actions"):
        evaluate_agent(
            make_agent("frontier"), "EKFSLAM-v0", [0], {"action": {"kind": kind}}, max_episode_steps=2
        )


class _Undeclared:
    """A user's own agent that declares no interface: taken at its word."""

    def reset(self, env, seed=None):
        self.space = env.action_space

    def act(self, observation):
        return self.space.sample()


def test_the_planners_run_by_name_in_their_own_interface(capsys):
    argv = [
        "--agent",
        "frontier-primitives,greedy-primitives",
        "--env-kwargs",
        '{"action": {"kind": "primitives"}}',
    ]
    assert main([*argv, "--json", "--seeds", "0", "--max-episode-steps", "3", "--no-progress"]) == 0
    obj = json.loads(capsys.readouterr().out)
    assert list(obj) == ["frontier-primitives", "greedy-primitives"]
    assert all(entry["metrics"]["path_length"]["iqm"] > 0 for entry in obj.values())
    rows = evaluate_agent(
        _Undeclared(), "EKFSLAM-v0", [0], {"action": {"kind": "primitives"}}, max_episode_steps=2
    )
    assert rows[0]["steps"] == 2

"""The Ray sweep end to end at smoke size: outputs, the JSON line, skipping finished trials, resuming interrupted
ones, and the held-out seeds refused. Never asserts learning quality."""

import contextlib
import io
import json

import pytest

pytest.importorskip("ray")
pytest.importorskip("stable_baselines3")

from ekfslam_gym.cli import sweep as cli  # noqa: E402
from ekfslam_gym.training import sweep  # noqa: E402

TINY = ["n_steps=256", "batch_size=256", "n_epochs=1", "n_envs=2", "eval_freq=0", "checkpoint_freq=0",
        "env_kwargs={max_episode_steps: 100}"]  # fmt: skip


def run_cli(argv):
    """(exit status, stdout lines, stderr) of the sweep command run in this process."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = cli.main(argv)
    return status, out.getvalue().splitlines(), err.getvalue()


@pytest.fixture(scope="module")
def finished_sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep")
    argv = ["--env-ids", "EKFSLAM-v0", "--seeds", "0-1", "--timesteps", "2048", "--eval-seeds", "20000-20001",
            "--out", str(out), "--workers", "2", "--json", "--hyperparams", *TINY]  # fmt: skip
    status, lines, err = run_cli(argv)
    return out, argv, status, lines, err


def test_sweep_trains_evaluates_and_tabulates_every_seed(finished_sweep):
    out, _, status, lines, err = finished_sweep
    assert status == 0, err
    report = json.loads(lines[-1])
    assert report["trained_steps"] == 2 * 2048 and report["failed"] == []
    table = report["results"]["EKFSLAM-v0"]
    assert sorted(table["seeds"]) == ["0", "1"]
    assert table["pooled"]["episodes"] == 4 and table["seeds"]["0"]["episodes"] == 2
    lo, hi = table["pooled"]["metrics"]["return"]["ci"]
    assert lo <= table["pooled"]["metrics"]["return"]["iqm"] <= hi
    assert json.loads((out / "sweep.json").read_text()) == report
    markdown = (out / "sweep.md").read_text()
    assert "| pooled | 4 |" in markdown and "| seed 1 | 2 |" in markdown
    for seed in (0, 1):
        trial = out / f"EKFSLAM-v0_seed{seed}"
        for name in (
            "model.zip",
            "model_vecnormalize.pkl",
            "config.yaml",
            "learning_curve.png",
            "result.json",
        ):
            assert (trial / name).is_file(), name
        result = json.loads((trial / "result.json").read_text())
        assert result["timesteps"] == 2048 and [e["seed"] for e in result["episodes"]] == [20000, 20001]
        assert all(e["steps"] == 100 for e in result["episodes"])  # the trained env's time limit
    # The per-seed row agrees with aggregating that trial's own episodes.
    again = cli.tabulate([json.loads((out / "EKFSLAM-v0_seed1" / "result.json").read_text())])
    assert again["EKFSLAM-v0"]["pooled"]["metrics"] == table["seeds"]["1"]["metrics"]


def test_second_run_skips_finished_trials(finished_sweep):
    out, argv, _, first_lines, _ = finished_sweep
    results = {p: p.read_bytes() for p in out.glob("*/result.json")}
    models = {p: p.stat().st_mtime_ns for p in out.glob("*/model.zip")}
    status, lines, err = run_cli(argv)
    assert status == 0
    assert err.count("skip EKFSLAM-v0_seed") == 2 and "queued" not in err
    assert {p: p.read_bytes() for p in out.glob("*/result.json")} == results
    assert {p: p.stat().st_mtime_ns for p in out.glob("*/model.zip")} == models
    report = json.loads(lines[-1])
    assert report["trained_steps"] == 0
    assert report["results"] == json.loads(first_lines[-1])["results"]


def test_interrupted_trial_resumes_from_its_checkpoint(finished_sweep):
    out = finished_sweep[0]
    trial_dir = out / "EKFSLAM-v0_seed1"
    (trial_dir / "result.json").unlink()  # as if the run stopped after its last checkpoint
    _, _, entry = sweep.read_run(trial_dir)
    trial = sweep.Trial("EKFSLAM-v0", 1, {**entry, "n_timesteps": 2560}, out, (20000,))
    assert sweep.trial_state(trial.folder) == "resume"
    result = sweep.run_trial(trial)  # in this process: Ray only schedules run_trial
    assert result["state"] == "resume" and result["timesteps"] == 2560 and result["trained_steps"] == 512
    assert sweep.trial_state(trial.folder) == "done"


def test_held_out_evaluation_seeds_are_refused(tmp_path, capsys):
    with pytest.raises(SystemExit):
        cli.main(["--seeds", "0", "--eval-seeds", "10040-10060", "--out", str(tmp_path)])
    assert "held-out suite 10000-10049" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())  # refused before anything ran
    trial = sweep.Trial("EKFSLAM-v0", 0, {"n_timesteps": 1}, tmp_path, (10001,))
    with pytest.raises(ValueError, match="held-out"):
        sweep.run_trial(trial)  # the task checks too, for callers that skip the command line

"""Every command line: one ``usage:`` style and one ``python -m`` style; the user's own bad input ending in one
line on stderr and exit status 2, anything deeper in a traceback; evaluate's single output per run (--format)."""

from __future__ import annotations

import importlib
import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import pytest
import tomllib

from ekfslam_gym.cli import common
from ekfslam_gym.cli.common import AGENT_NAMES, command_line

ROOT = Path(__file__).resolve().parents[2]
SCRIPTS = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
SHORT = ["--seeds", "0", "--max-episode-steps", "3", "--no-progress"]


def _entry(script: str):
    module, _, function = SCRIPTS[script].partition(":")
    return getattr(importlib.import_module(module), function)


def _fails(capsys, main, argv, *fragments: str, status: int = 2) -> str:
    """``main(argv)`` exits with ``status``, and stderr's last line names every fragment, with no traceback."""
    with pytest.raises(SystemExit) as info:
        main([str(a) for a in argv])
    assert info.value.code == status
    err = capsys.readouterr().err
    assert "Traceback" not in err
    last = err.strip().splitlines()[-1]
    for fragment in fragments:
        assert fragment in last, (fragment, last)
    return last


# ---------------------------------------------------------------------------------------------- usage style
def test_every_console_script_is_named_ekfslam_dash_command_line():
    assert SCRIPTS and all(name.startswith("ekfslam-") for name in SCRIPTS)


@pytest.mark.parametrize("script", sorted(SCRIPTS))
def test_every_help_reads_usage_ekfslam_name(script, capsys):
    with pytest.raises(SystemExit) as info:
        _entry(script)(["--help"])
    assert info.value.code == 0
    assert capsys.readouterr().out.startswith(f"usage: {script} ")


def test_python_dash_m_shows_the_same_usage_as_the_console_script():
    """``python -m ekfslam_gym.cli.<name>`` runs the same main: its --help names the installed command."""
    for script, target in SCRIPTS.items():
        module = target.partition(":")[0]
        assert module == "ekfslam_gym.cli." + script.removeprefix("ekfslam-")
        run = subprocess.run(
            [sys.executable, "-m", module, "--help"], capture_output=True, text=True, cwd=ROOT
        )
        assert run.returncode == 0, (module, run.stderr)
        assert run.stdout.startswith(f"usage: {script} "), (module, run.stdout[:80])


def test_the_package_has_no_other_python_dash_m_entry_point():
    """One ``python -m`` style: no module outside ``ekfslam_gym/cli/`` runs a command line (``compiled.py``, run
    as a script, prints the kernels' sources for the Makefile: a build step, not a command)."""
    package = ROOT / "ekfslam_gym"
    others = sorted(
        str(path.relative_to(ROOT))
        for path in package.rglob("*.py")
        if "cli" not in path.relative_to(package).parts[:1]
        and (path.name == "__main__.py" or 'if __name__ == "__main__"' in path.read_text())
    )
    assert others == ["ekfslam_gym/compiled.py"]


@pytest.mark.parametrize("script", sorted(SCRIPTS))
def test_help_imports_only_what_the_parser_needs(script):
    """``--help`` runs without SciPy, torch, SB3, matplotlib or the agents (numba): each costs a large part of a
    second or more at start-up (bench/startup.py times them)."""
    heavy = ("scipy", "torch", "stable_baselines3", "matplotlib", "ekfslam_gym.agents", "numba")
    code = (
        "import contextlib, io, sys\n"
        f"from {SCRIPTS[script].replace(':', ' import ')}\n"
        "with contextlib.redirect_stdout(io.StringIO()), contextlib.suppress(SystemExit):\n"
        "    main(['--help'])\n"
        f"print(sorted(m for m in {heavy!r} if m in sys.modules))\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "[]", f"{script} --help imports {run.stdout.strip()}"


def test_the_help_names_written_out_are_the_library_ones():
    from ekfslam_gym.agents import AGENTS

    from ekfslam_gym.cli.graph import BACKEND_CHOICES
    from ekfslam_gym.graph.sparse_solve import BACKENDS

    assert AGENT_NAMES == tuple(AGENTS)
    assert BACKEND_CHOICES == ("auto", *BACKENDS)


# ---------------------------------------------------------------------------------------------- the wrapper
def _raiser(error: BaseException):
    @command_line("demo")
    def main(argv=None) -> int:
        raise error

    return main


@pytest.mark.parametrize(
    "error, line",
    [
        (SystemExit("configs/ppo.yaml has no entry for 'X'"), "ekfslam-demo: error: configs/ppo.yaml has no entry for 'X'"),
        (SystemExit("two\nlines"), "ekfslam-demo: error: two lines"),
    ],
)  # fmt: skip
def test_an_exit_with_a_message_is_one_line_and_exit_2(error, line, capsys):
    with pytest.raises(SystemExit) as info:
        _raiser(error)()
    assert info.value.code == 2
    assert capsys.readouterr().err == line + "\n"


@pytest.mark.parametrize(
    "error",
    [ValueError("a deep check"), KeyError("a missing key"), FileNotFoundError(2, "No such file", "x.zip"),
     RuntimeError("boom")],
)  # fmt: skip
def test_a_deep_error_propagates_with_its_traceback(error, capsys):
    """Only the command's own checks of the user's input exit 2: anything raised below ``main`` is not
    reported as a usage error, whatever its type."""
    with pytest.raises(type(error)):
        _raiser(error)()
    assert capsys.readouterr().err == ""


def test_a_deep_error_ends_the_process_with_a_traceback_and_status_1(tmp_path):
    """A console script run on a file whose reading fails deep inside (not a check of main's) exits 1 with
    Python's traceback."""
    code = (
        "from ekfslam_gym.cli import common\n"
        "@common.command_line('demo')\n"
        "def main(argv=None):\n"
        "    {}['filter']\n"
        "raise SystemExit(main())\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert run.returncode == 1
    assert "Traceback" in run.stderr and "KeyError: 'filter'" in run.stderr


def test_exit_statuses_and_return_values_pass_through(capsys):
    @command_line("demo")
    def main(argv=None):
        if argv == ["--help"]:
            raise SystemExit(0)
        return Path("runs/x")

    assert main() == Path("runs/x")
    with pytest.raises(SystemExit) as info:
        main(["--help"])
    assert info.value.code == 0 and capsys.readouterr().err == ""


def test_ctrl_c_exits_130(capsys):
    with pytest.raises(SystemExit) as info:
        _raiser(KeyboardInterrupt())()
    assert info.value.code == 130 and "interrupted" in capsys.readouterr().err


def test_json_object_names_the_parse_error():
    import argparse

    with pytest.raises(argparse.ArgumentTypeError, match="not valid JSON"):
        common.json_object('{"world": ')
    with pytest.raises(argparse.ArgumentTypeError, match="expected a JSON object"):
        common.json_object("[1]")
    assert common.json_object('{"a": {"b": 1}}') == {"a": {"b": 1}}


# ---------------------------------------------------------------------------------------------- each command
@pytest.mark.parametrize(
    "argv, fragments",
    [
        (["--agent", "circle", "--agent-kwargs", '{"circle": {"radiu": 3}}'],
         ["--agent-kwargs", "circle takes no argument 'radiu'", "radius"]),
        (["--agent", "circle", "--agent-kwargs", '{"circle": {"radius": -3}}'], ["--agent-kwargs circle", "radius > 0"]),
        (["--agent", "circle", "--agent-kwargs", '{"greedy": {}}'], ["--agent-kwargs", "['greedy'] not among"]),
        (["--agent", "circle", "--agent-kwargs", '{"circle": 3}'], ["--agent-kwargs", "'circle' is not a JSON object"]),
        (["--agent", "circle", "--agent-kwargs", '{"circle": '], ["argument --agent-kwargs", "not valid JSON"]),
        (["--agent", "ppo", "--model", "no/such/model.zip"], ["--model no/such/model.zip", "no saved model"]),
        (["--agent", "circle", "--env-kwargs", '{"world": {"n_landmark": 3}}'],
         ["--env-kwargs", "unknown config field world.n_landmark", "n_landmarks"]),
        (["--agent", "circle", "--env-id", "NoSuchEnv-v0"], ["--env-id NoSuchEnv-v0", "EKFSLAM-v0"]),
        (["--agent", "circle", "--seeds", "5-1"], ["argument --seeds"]),
        (["--agent", "circle", "--format", "table", "--json"], ["--json is --format json", "--format table"]),
        (["--agent", "circle", "--format", "wide"], ["argument --format", "blocks", "table", "json"]),
    ],
)  # fmt: skip
def test_evaluate_bad_input(argv, fragments, capsys):
    from ekfslam_gym.cli.evaluate import main

    _fails(capsys, main, [*SHORT, *argv], "ekfslam-evaluate: error:", *fragments)


@pytest.mark.parametrize(
    "argv, fragments",
    [
        (["--agents", "ppo", "--model", "no/such/model"], ["--model no/such/model", "no saved model"]),
        (["--env-kwargs", '{"filter": {"variant": 3}}'], ["--env-kwargs", "filter.variant must be a string"]),
        (["--env-id", "NoSuchEnv-v0"], ["--env-id NoSuchEnv-v0"]),
        (["--filters", "ukf"], ["unknown filter variant", "'ekf', 'fej', 'iekf'"]),
        (["--steps", "0"], ["--steps must be positive"]),
    ],
)  # fmt: skip
def test_consistency_bad_input(argv, fragments, capsys):
    from ekfslam_gym.cli.consistency import main

    _fails(capsys, main, ["--seeds", "0", "--steps", "3", *argv], "ekfslam-consistency: error:", *fragments)


@pytest.mark.parametrize(
    "argv, fragments",
    [
        (["--seeds", "x"], ["argument --seeds"]),
        (["--agent", "teleport"], ["--agent", "unknown agent 'teleport'", "circle"]),
        (["--env-id", "NoSuchEnv-v0"], ["--env-id NoSuchEnv-v0"]),
    ],
)
def test_smoothing_bad_input(argv, fragments, capsys):
    from ekfslam_gym.cli.smoothing import main

    _fails(capsys, main, argv, "ekfslam-smoothing: error:", *fragments)


def test_compare_tradeoff_sweep_and_replay_name_a_missing_file(tmp_path, capsys):
    from ekfslam_gym.cli import compare, replay, sweep, tradeoff

    missing = tmp_path / "missing.json"
    _fails(capsys, compare.main, ["--a", missing, "--b", missing], "ekfslam-compare: error:", "missing.json")
    _fails(capsys, tradeoff.main, [missing], "ekfslam-tradeoff: error:", "missing.json")
    _fails(capsys, sweep.main, ["--seeds", "0", "--config", tmp_path / "nope.yaml"], "ekfslam-sweep: error:",
           "nope.yaml does not exist")  # fmt: skip
    _fails(capsys, replay.main, ["--data", tmp_path / "nope.dat"], "ekfslam-replay: error:", "nope.dat")


def test_sweep_names_a_bad_setting_before_any_trial(tmp_path, capsys):
    """A setting's error comes from the library as a ValueError (SettingsError); the command names it, exit 2."""
    from ekfslam_gym.cli.sweep import main

    base = ["--seeds", "0", "--out", tmp_path / "sweep"]
    _fails(capsys, main, [*base, "--hyperparams", "n_steps"], "ekfslam-sweep: error:", "KEY=VALUE")
    _fails(
        capsys, main, [*base, "--hyperparams", "learning_rat=0.1"], "ekfslam-sweep: error:", "learning_rat"
    )
    assert not (tmp_path / "sweep").exists()


def test_train_script_bad_input_is_one_line(tmp_path):
    """``python train.py``: a missing config and a misspelt --hyperparams key end in one line, no traceback."""
    cases = [
        (["--config", str(tmp_path / "nope.yaml")], "nope.yaml does not exist"),
        (["--config", str(ROOT / "configs/ppo.yaml"), "--hyperparams", "learning_rate"], "KEY=VALUE"),
        (["--config", str(ROOT / "configs/ppo.yaml"), "--hyperparams", "learning_rat=0.1", "--timesteps", "8",
          "--out", str(tmp_path / "run"), "--no-progress"], "learning_rat"),
    ]  # fmt: skip
    for argv, fragment in cases:
        run = subprocess.run([sys.executable, str(ROOT / "train.py"), *argv], capture_output=True, text=True,
                             cwd=tmp_path)  # fmt: skip
        assert run.returncode != 0 and "Traceback" not in run.stderr, run.stderr
        last = run.stderr.strip().splitlines()[-1]
        assert fragment in last and ": error: " in last, last


# ---------------------------------------------------------------------------------------------- --format
def test_evaluate_prints_one_output_per_evaluation(capsys):
    from ekfslam_gym.cli.evaluate import main

    argv = ["--agent", "circle,random", *SHORT]
    assert main(argv) == 0
    blocks = capsys.readouterr().out
    assert "circle: 1 episodes" in blocks and "random: 1 episodes" in blocks and "| agent |" not in blocks
    assert main([*argv, "--format", "table"]) == 0
    table = capsys.readouterr().out
    assert "| circle | 1 |" in table and "| random | 1 |" in table and "episodes\n" not in table
    assert main([*argv, "--format", "json"]) == 0
    as_json = json.loads(capsys.readouterr().out)
    assert main([*argv, "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == as_json and list(as_json) == ["circle", "random"]


# ---------------------------------------------------------------------------------------------- docs page
@pytest.fixture(scope="module")
def page_script():
    spec = importlib.util.spec_from_file_location("command_lines_page", ROOT / "docs" / "command_lines.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_command_lines_page_is_what_the_parsers_give(page_script, capsys):
    assert page_script.main(["--check"]) == 0, "run: python docs/command_lines.py"
    text = page_script.PAGE.read_text()
    for script in SCRIPTS:
        assert f"\n## {script}\n" in text and f"usage: {script} " in text


def test_the_page_check_fails_on_a_stale_page(page_script, tmp_path, monkeypatch, capsys):
    stale = tmp_path / "command-lines.md"
    stale.write_text(page_script.PAGE.read_text().replace("--agent-kwargs", "--agent-kwarg"))
    monkeypatch.setattr(page_script, "PAGE", stale)
    assert page_script.main(["--check"]) == 1
    assert "out of date" in capsys.readouterr().err


@pytest.mark.parametrize(
    "flags, example, message",
    [
        (("--agent", "--no-such-flag"), "ekfslam-evaluate --agent circle", "--no-such-flag"),
        (("--agent",), "ekfslam-evaluate --agent circle --no-such-flag 3", "ekfslam-evaluate"),
    ],
)
def test_a_main_flag_or_an_example_the_parser_refuses_fails_the_page(
    page_script, monkeypatch, flags, example, message
):
    from ekfslam_gym.cli.evaluate import main

    does = page_script.COMMANDS["ekfslam-evaluate"][0]
    monkeypatch.setitem(page_script.COMMANDS, "ekfslam-evaluate", (does, flags, example))
    with pytest.raises(ValueError, match=message):
        page_script.check_example("ekfslam-evaluate", page_script.parser_of(main))

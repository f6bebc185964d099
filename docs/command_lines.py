"""Write docs/command-lines.md from the command lines' own parsers: every console script of pyproject.toml (and
``python train.py`` while it has none), what it does, its main flags, an example, and every flag's help.

    python docs/command_lines.py           # rewrite the page
    python docs/command_lines.py --check   # exit 1 if the page is not what the parsers give (CI, tests)

Each parser is taken from its command's own ``main``: ``main`` runs until it parses its arguments, and is stopped
there, so nothing here repeats a flag by hand. The examples and the choice of main flags are written below and
checked against the parsers: an example that its parser refuses, or a main flag it does not have, fails.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any
from unittest import mock

import tomllib

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "command-lines.md"
WIDTH = "110"  # argparse wraps usage lines to $COLUMNS: fixed, so the page does not depend on the terminal

# Per command, in the page's order: (what it does, main flags, example); the example's words after the command are
# parsed by its parser. A command missing here still gets a row, from its parser alone.
COMMANDS: dict[str, tuple[str, tuple[str, ...], str]] = {
    "ekfslam-evaluate": (
        "Run agents on a seed suite: per-episode metrics, IQM with bootstrap CIs, tables, plots, GIFs, TUM files.",
        ("--agent", "--model", "--seeds", "--format", "--table"),
        "ekfslam-evaluate --agent circle,greedy --seeds 20000-20004 --format table",
    ),
    "ekfslam-benchmark": (
        "The standard protocol: an agent on the held-out suite of every env, beside the reference rows.",
        ("--agent", "--model", "--env-ids", "--quick", "--out"),
        "ekfslam-benchmark --agent frontier --env-ids EKFSLAM-v0",
    ),
    "ekfslam-compare": (
        "Two groups of evaluated models on the same seeds: the difference of their IQMs with a paired bootstrap CI.",
        ("--a", "--b", "--key", "--metric"),
        "ekfslam-compare --a new_s0.json new_s1.json --b old_s0.json old_s1.json",
    ),
    "ekfslam-tradeoff": (
        "Two metrics against each other for many models; the Pareto front.",
        ("FILE", "--x", "--y", "--plot", "--csv"),
        "ekfslam-tradeoff runs/ppo.json runs/planners.json --plot tradeoff.png",
    ),
    "ekfslam-consistency": (
        "The filter's NEES and NIS against their chi-squared bands, per agent and filter variant.",
        ("--agents", "--filters", "--seeds", "--steps", "--plot"),
        "ekfslam-consistency --agents random,circle --filters ekf,fej --seeds 0-9",
    ),
    "ekfslam-smoothing": (
        "The filter against the full-SLAM smoother on the same episodes.",
        ("--agent", "--seeds", "--json"),
        "ekfslam-smoothing --agent circle --seeds 20000-20004",
    ),
    "ekfslam-replay": (
        "Replay a drive through EKF-SLAM: the simulated drive, or course-format files.",
        ("--data", "--world", "--steps", "--plot", "--tum"),
        "ekfslam-replay --steps 120 --plot replay.png",
    ),
    "ekfslam-graph": (
        "Solve a pose graph file (course .dat, g2o) by Gauss-Newton or Levenberg-Marquardt.",
        ("file", "--solver", "--json", "--plot"),
        "ekfslam-graph intel.g2o --solver lm --json",
    ),
    "ekfslam-sweep": (
        "Train and evaluate PPO over env ids x training seeds on Ray, and tabulate the evaluations.",
        ("--env-ids", "--seeds", "--timesteps", "--out", "--address"),
        "ekfslam-sweep --env-ids EKFSLAM-v0 --seeds 0-4 --timesteps 200000 --out runs/sweep",
    ),
    "ekfslam-train": (
        "Train PPO on an env from a config in rl-zoo3's format.",
        ("--config", "--env-id", "--timesteps", "--seed", "--hyperparams", "--resume"),
        "ekfslam-train --config configs/ppo.yaml --env-id EKFSLAM-v0 --timesteps 200000 --seed 0",
    ),
}
_train = COMMANDS["ekfslam-train"]  # the repository's script runs the same command line
COMMANDS["train.py"] = (*_train[:2], _train[2].replace("ekfslam-train", "python train.py", 1))


class _Parsed(BaseException):
    """Carries the parser out of ``main`` (a BaseException, so that the command-line wrapper lets it pass)."""


@contextmanager
def _stop_at_parsing() -> Iterator[None]:
    def capture(self: argparse.ArgumentParser, *args: Any, **kwargs: Any) -> Any:
        raise _Parsed(self)

    with mock.patch.object(argparse.ArgumentParser, "parse_args", capture):
        yield


def parser_of(main: Callable[..., Any]) -> argparse.ArgumentParser:
    """The parser ``main`` builds, taken at its ``parse_args`` call."""
    with _stop_at_parsing():
        try:
            main([])
        except _Parsed as parsed:
            return parsed.args[0]
    raise RuntimeError(f"{main.__module__}.{main.__name__} never parsed its arguments")


def commands() -> dict[str, Callable[..., Any]]:
    """Command name -> main: pyproject.toml's console scripts, then ``train.py`` unless ``ekfslam-train`` is one."""
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    found = {}
    for name, target in scripts.items():
        module, _, function = target.partition(":")
        found[name] = getattr(importlib.import_module(module), function)
    if "ekfslam-train" not in found and (ROOT / "train.py").is_file():
        sys.path.insert(0, str(ROOT))
        try:
            found["train.py"] = importlib.import_module("train").main
        finally:
            sys.path.remove(str(ROOT))
    return found


def _flag(action: argparse.Action) -> str:
    if action.option_strings:
        return ", ".join(action.option_strings)
    return action.metavar if isinstance(action.metavar, str) else action.dest


def _default(action: argparse.Action) -> str:
    value = action.default
    if value is None or value is False or value == [] or action.nargs == 0 or value is argparse.SUPPRESS:
        return ""
    if isinstance(value, (list, tuple)) and len(value) > 3 and all(isinstance(v, int) for v in value):
        if list(value) == list(range(value[0], value[0] + len(value))):
            return f"`{value[0]}-{value[-1]}`"
    return f"`{value}`"


def _cell(text: str) -> str:
    """Text for a Markdown table cell: one line, no column break, no HTML tag (``<model>.zip`` stays visible)."""
    return " ".join(text.split()).replace("|", "\\|").replace("<", "&lt;").replace(">", "&gt;")


def _help(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    text = action.help or ""
    if "%(" in text:
        text = text % {**vars(action), "prog": parser.prog, "default": action.default}
    choices = [str(c) for c in action.choices or ()]
    if choices and not all(c in text for c in choices):
        text += (" " if text else "") + "(one of " + ", ".join(choices) + ")"
    return _cell(text)


def _options(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    return [a for a in parser._actions if not isinstance(a, argparse._HelpAction)]


def _description(parser: argparse.ArgumentParser) -> str:
    """The description's first paragraph on one line, its reStructuredText literals as Markdown's."""
    return _cell((parser.description or "").strip().split("\n\n")[0].replace("``", "`"))


def entry(name: str, parser: argparse.ArgumentParser) -> tuple[str, tuple[str, ...], str]:
    """(what it does, main flags, example): ``COMMANDS``' or, for a command not there, the parser's own."""
    if name in COMMANDS:
        return COMMANDS[name]
    flags = tuple(_flag(a) for a in _options(parser) if a.required or not a.option_strings)
    flags += tuple(_flag(a) for a in _options(parser) if a.option_strings)[: max(0, 4 - len(flags))]
    return _description(parser), flags, f"{name} --help"


def check_example(name: str, parser: argparse.ArgumentParser) -> None:
    """The example parses and every main flag exists; ValueError otherwise."""
    _, flags, example = entry(name, parser)
    words = example.split()
    words = words[2:] if words[0] == "python" else words[1:]
    names = {_flag(a) for a in _options(parser)} | {s for a in _options(parser) for s in a.option_strings}
    if missing := [f for f in flags if f not in names]:
        raise ValueError(f"{name}: main flags {missing} are not among its flags {sorted(names)}")
    with mock.patch.object(argparse.ArgumentParser, "exit", side_effect=ValueError(f"{name}: {example!r}")):
        with mock.patch.object(argparse.ArgumentParser, "print_usage"), mock.patch("sys.stderr"):
            parser.parse_args(words)


def render() -> str:
    found = commands()
    order = [n for n in COMMANDS if n in found] + [n for n in found if n not in COMMANDS]
    with mock.patch.dict(os.environ, {"COLUMNS": WIDTH}):
        parsers = {}
        for name in order:  # a parser without a prog takes its name from sys.argv[0], as when run as NAME
            with mock.patch.object(sys, "argv", [name]):
                parsers[name] = parser_of(found[name])
        usages = {name: parser.format_usage().strip() for name, parser in parsers.items()}
    lines = [
        "# Command lines",
        "",
        "<!-- Generated by docs/command_lines.py from the commands' parsers: edit the parsers (or the examples in",
        "     that script), then run `python docs/command_lines.py`. -->",
        "",
        "Every command is installed with the package as a console script `ekfslam-<name>`, the name its `--help`",
        "shows; `python -m ekfslam_gym.cli.<name>` runs the same command. Training is also `python train.py` from a",
        "checkout of the repository.",
        "",
        "**Errors.** Your own bad input (a flag, a value, a file you named) ends in one line on stderr that names",
        "the flag, what was wrong and what is allowed, and exit status 2, as argparse's own errors do:",
        "",
        "```console",
        '$ ekfslam-evaluate --agent circle --agent-kwargs \'{"circle": {"radiu": 3}}\'',
        "ekfslam-evaluate: error: --agent-kwargs: circle takes no argument 'radiu'; it takes radius, speed",
        "$ echo $?",
        "2",
        "```",
        "",
        "Any other failure is not a usage error: it ends in Python's traceback, exit status 1, for a bug report.",
        "Ctrl-C exits with status 130.",
        "",
        "## The commands",
        "",
        "| command | what it does | main flags | example |",
        "|---|---|---|---|",
    ]
    for name, parser in parsers.items():
        check_example(name, parser)
        does, flags, example = entry(name, parser)
        main = ", ".join(f"`{f}`" for f in flags)
        lines.append(f"| [`{name}`](#{name.replace('.', '')}) | {does} | {main} | `{example}` |")
    for name, parser in parsers.items():
        lines += ["", f"## {name}", "", "```text", usages[name], "```", ""]
        lines += [_description(parser), "", "| flag | default | meaning |", "|---|---|---|"]
        for action in _options(parser):
            lines.append(f"| `{_flag(action)}` | {_default(action)} | {_help(parser, action)} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--check", action="store_true", help="exit 1 if the page is out of date; write nothing"
    )
    args = parser.parse_args(argv)
    text = render()
    if args.check:
        if not PAGE.is_file() or PAGE.read_text() != text:
            print(f"{PAGE.name} is out of date: run python docs/command_lines.py", file=sys.stderr)
            return 1
        return 0
    PAGE.write_text(text)
    print(f"wrote docs/{PAGE.name}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""What the command lines share: their names, the wrapper every ``main`` goes through, argument types.

Every command is installed as ``ekfslam-<name>`` (pyproject.toml's ``[project.scripts]``) and its parser is
built by ``command_parser(name)``, so that ``--help`` reads ``usage: ekfslam-<name> ...`` however it was started
(``python -m ekfslam_gym.cli.<name>`` runs the same ``main``).

Exit statuses: 2 for the user's own input, and only that: argparse's errors, and the checks a ``main`` makes of
the flags, values and files it was given, each through ``parser.error("--flag: what was wrong; what is
allowed")`` (one line on stderr, ``ekfslam-<name>: error: ...``). Anything raised deeper is a bug or a broken
environment, not a usage error: it propagates with its traceback (exit status 1), whatever its type. A ``main``
gets the rest by ``@command_line("<name>")``:

    @command_line("train")
    def main(argv: Sequence[str] | None = None) -> int:
        parser = command_parser("train", description=...)
        args = parser.parse_args(argv)
        ...

``SystemExit`` with a status (argparse's, ``--help``'s) passes through untouched; ``SystemExit("message")`` is
printed as an error and exits 2; Ctrl-C exits 130. A command's module imports at its top only what its parser
needs, and the rest inside ``main`` once the arguments are read, so ``--help`` starts fast.
"""

from __future__ import annotations

import argparse
import functools
import inspect
import json
import sys
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, NoReturn

from .. import seeds

AGENT_NAMES: tuple[str, ...] = (
    "random", "circle", "lawnmower", "greedy", "greedy2", "frontier", "ppo",
    "greedy-primitives", "frontier-primitives", "frontier-waypoint",
)  # fmt: skip
"""The names ``ekfslam_gym.agents.AGENTS`` registers, for the parsers' help: importing the agents (numba, SciPy)
would triple a ``--help``'s time. tests/cli/test_command_lines.py holds the two equal."""

USAGE_EXIT = 2  # argparse's status for a usage error
INTERRUPTED_EXIT = 130  # the shell's 128 + SIGINT


def prog_name(command: str) -> str:
    """``ekfslam-<command>``: the installed console script, the name every ``usage:`` line shows."""
    return f"ekfslam-{command}"


def command_parser(command: str, **kwargs: Any) -> argparse.ArgumentParser:
    """An ``ArgumentParser`` named ``ekfslam-<command>`` (keyword arguments as ``ArgumentParser``'s)."""
    return argparse.ArgumentParser(prog=prog_name(command), **kwargs)


def module_docstring(name: str) -> str:
    """The docstring of module ``name`` read from its source, without running it: a parser's description can
    quote a heavy module (torch, SB3) and ``--help`` still start fast."""
    import ast
    import importlib.util

    spec = importlib.util.find_spec(name)
    if spec is None or spec.origin is None:
        raise ModuleNotFoundError(f"no module named {name!r}", name=name)
    return ast.get_docstring(ast.parse(Path(spec.origin).read_text(encoding="utf-8")), clean=False) or ""


def error_message(error: BaseException) -> str:
    """One line that says what was wrong, without Python's decoration (a KeyError's quotes, OSError's errno)."""
    if isinstance(error, KeyError) and len(error.args) == 1:
        text = str(error.args[0])
    elif isinstance(error, OSError) and error.filename is not None and error.strerror:
        text = f"{error.filename}: {error.strerror.lower()}"
    else:
        text = str(error) or type(error).__name__
    return " ".join(text.split())  # one line


def refuse(parser: argparse.ArgumentParser, flag: str, error: BaseException) -> NoReturn:
    """End the command on an input the user named (``flag``: the option, with its value where that helps; empty
    when the error names the file itself) with the message of the ``error`` reading it raised: one line on
    stderr, ``<prog>: error: ...``, and exit status 2. No usage line: the command line was right, the file or
    value it named was not."""
    message = f"{flag}: {error_message(error)}" if flag else error_message(error)
    parser.exit(USAGE_EXIT, f"{parser.prog}: error: {message}\n")


def command_line(command: str, prog: str | None = None) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Decorate a command's ``main(argv)``: a ``SystemExit("message")`` becomes one line and exit status 2,
    Ctrl-C one line and 130; everything else passes through (see the module docstring). The lines start with
    ``prog`` (default ``ekfslam-<command>``)."""
    prog = prog or prog_name(command)

    def decorate(main: Callable[..., Any]) -> Callable[..., int]:
        @functools.wraps(main)
        def guarded(*args: Any, **kwargs: Any) -> Any:
            try:
                return main(*args, **kwargs)
            except SystemExit as exit:  # sys.exit("message"): a message in place of a status is an error too
                if isinstance(exit.code, str):
                    print(f"{prog}: error: {' '.join(exit.code.split())}", file=sys.stderr)
                    raise SystemExit(USAGE_EXIT) from None
                raise
            except KeyboardInterrupt:
                print(f"{prog}: interrupted", file=sys.stderr)
                raise SystemExit(INTERRUPTED_EXIT) from None

        return guarded

    return decorate


def check_agent_interface(
    parser: argparse.ArgumentParser,
    label: str,
    agent: Any,
    env_id: str,
    env_kwargs: Mapping[str, Any] | None,
    flag: str = "--agent",
) -> None:
    """Refuse, against ``flag``, an agent that acts in another interface than the env it would run in (a
    velocity command would be read as a waypoint goal without a word), naming the agents that act in the
    env's. ``ekfslam_gym.evaluation.interface.check_action_kind`` says the same to a library caller."""
    from ekfslam_gym.agents import AGENTS
    from ekfslam_gym.evaluation.interface import check_action_kind
    from ekfslam_gym.evaluation.rollout import make_env

    env = make_env(env_id, env_kwargs)  # as the episodes will be built
    try:
        check_action_kind(agent, env)
    except ValueError as error:
        kind = env.unwrapped.config.action.kind
        fitting = [name for name, cls in AGENTS.items() if name != "ppo" and str(cls.action_kind) == kind]
        parser.error(
            f"{flag} {label}: {error_message(error)} ({', '.join(fitting)}, or a policy trained in it)"
        )
    finally:
        env.close()


def json_object(text: str) -> dict[str, Any]:
    """An argparse type: a JSON object (``{"world": {"n_landmarks": 50}}``), with the parse error's position."""
    try:
        value = json.loads(text)
    except json.JSONDecodeError as error:
        raise argparse.ArgumentTypeError(f"not valid JSON ({error}): {text!r}") from None
    if not isinstance(value, dict):
        raise argparse.ArgumentTypeError(f"expected a JSON object {{...}}, got {text!r}")
    return value


def agent_from_flags(
    parser: argparse.ArgumentParser, name: str, kwargs: Mapping[str, Any], model: str | Path | None = None
) -> Any:
    """``make_agent(name, **kwargs)`` (with ``model_path=model`` for a policy) whose failures name their flag:
    an argument the agent does not take (``--agent-kwargs``, with the ones it takes), a value it refuses, or a
    missing saved model (``--model``)."""
    from ekfslam_gym.agents import AGENTS, make_agent

    # The signature of a registered agent is checked here; any other name is make_agent's to resolve or refuse.
    parameters = inspect.signature(AGENTS[name]).parameters if name in AGENTS else {}
    takes_any = name not in AGENTS or any(
        p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters.values()
    )
    allowed = [n for n, p in parameters.items() if p.kind is not inspect.Parameter.VAR_KEYWORD]
    unknown = sorted(set(kwargs) - set(allowed)) if not takes_any else []
    if unknown:
        parser.error(
            f"--agent-kwargs: {name} takes no argument {', '.join(map(repr, unknown))}; it takes "
            f"{', '.join(a for a in allowed if a not in ('model', 'model_path')) or 'none'}"
        )
    extra = {"model_path": model} if model is not None else {}
    try:
        return make_agent(name, **extra, **kwargs)
    except FileNotFoundError as error:
        if model is None:
            raise
        parser.error(f"--model {model}: {error_message(error)}")
    except (TypeError, ValueError) as error:  # make_agent's ValueError names an unknown agent
        parser.error(f"{'--agent-kwargs' if kwargs else '--agent'} {name}: {error_message(error)}")


def parse_seeds(text: str) -> list[int]:
    """``--seeds``: a suite's name (``heldout``, ``eval``), ``A-B`` (inclusive), ``A,B,C``, or a mix such as
    ``0-4,10`` (``ekfslam_gym.seeds.parse_seeds``)."""
    try:
        return seeds.parse_seeds(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def check_env_flags(
    parser: argparse.ArgumentParser, env_id: str, env_kwargs: Mapping[str, Any] | None = None
) -> None:
    """Build the env once so that an unknown ``--env-id`` or a setting the config refuses (``--env-kwargs``) is
    reported against its flag before any episode runs (a build costs a fraction of a second)."""
    import gymnasium as gym

    import ekfslam_gym  # noqa: F401  (registers the ids)

    try:
        gym.make(env_id, **(env_kwargs or {})).close()
    except gym.error.Error as error:
        known = sorted(k for k in gym.registry if "EKFSLAM" in k)
        parser.error(f"--env-id {env_id}: {error_message(error)} (this package registers {', '.join(known)})")
    except (ValueError, TypeError, KeyError, OSError) as error:
        parser.error(f"--env-kwargs: {error_message(error)}")

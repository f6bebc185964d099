"""What the command lines share: their names, the wrapper every ``main`` goes through, argument types.

Every command is installed as ``ekfslam-<name>`` (pyproject.toml's ``[project.scripts]``) and its parser is
built by ``command_parser(name)``, so that ``--help`` reads ``usage: ekfslam-<name> ...`` however it was started
(``python -m ekfslam_gym.<name>`` runs the same ``main``).

Bad input ends in one line on stderr, ``ekfslam-<name>: error: <what was wrong>``, and exit status 2, as
argparse's own ``parser.error`` does; a traceback only when ``EKFSLAM_DEBUG`` is set (to anything but ``0`` or
the empty string). A ``main`` gets this by ``@command_line("<name>")``:

    @command_line("train")
    def main(argv: Sequence[str] | None = None) -> int:
        parser = command_parser("train", description=...)
        args = parser.parse_args(argv)
        ...  # parser.error("--flag: what was wrong; what is allowed") for the checks main makes itself

Errors raised below ``main`` are mapped by type (``USER_ERRORS``): ``ValueError`` (the config's validation
errors are ValueErrors: ``unknown config field world.n_landmark; known: [...]``), ``KeyError``, ``OSError``
(a missing file), ``yaml.YAMLError`` and Gymnasium's ``gymnasium.error.Error`` (an unknown env id) exit 2 with
their message; any other exception is a bug, reported in one line with exit status 1 and the hint to set
``EKFSLAM_DEBUG=1``; Ctrl-C exits 130. ``SystemExit`` with a status (argparse's, ``--help``'s) passes through
untouched; ``SystemExit("message")`` is printed as an error and exits 2.
The wrapper cannot know which flag a deep error came from: checks that can name their flag belong in ``main``
(``agent_from_flags`` below is one).
"""

from __future__ import annotations

import argparse
import functools
import inspect
import json
import os
import sys
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from .. import seeds

DEBUG_ENV = "EKFSLAM_DEBUG"
"""Set this environment variable (``EKFSLAM_DEBUG=1``) to see the traceback of an error instead of one line."""

USAGE_EXIT = 2  # argparse's status for a usage error
BUG_EXIT = 1
INTERRUPTED_EXIT = 130  # the shell's 128 + SIGINT

USER_ERRORS: tuple[type[BaseException], ...] = (ValueError, KeyError, OSError)
"""Exception types that mean bad input (a value, a name, a file); more are added by module when loaded (YAML's and
Gymnasium's errors, see ``_user_error_types``)."""


def prog_name(command: str) -> str:
    """``ekfslam-<command>``: the installed console script, the name every ``usage:`` line shows."""
    return f"ekfslam-{command}"


def command_parser(command: str, **kwargs: Any) -> argparse.ArgumentParser:
    """An ``ArgumentParser`` named ``ekfslam-<command>`` (keyword arguments as ``ArgumentParser``'s)."""
    return argparse.ArgumentParser(prog=prog_name(command), **kwargs)


def debugging() -> bool:
    """Whether ``EKFSLAM_DEBUG`` asks for tracebacks."""
    return os.environ.get(DEBUG_ENV, "") not in ("", "0")


def _user_error_types() -> tuple[type[BaseException], ...]:
    """``USER_ERRORS`` plus the error bases of YAML and Gymnasium when they are loaded (an error of theirs can only
    have been raised if they are: no import here)."""
    extra = []
    for module, name in (("yaml", "YAMLError"), ("gymnasium.error", "Error")):
        loaded = sys.modules.get(module)
        if loaded is not None and isinstance(getattr(loaded, name, None), type):
            extra.append(getattr(loaded, name))
    return USER_ERRORS + tuple(extra)


def error_message(error: BaseException) -> str:
    """One line that says what was wrong, without Python's decoration (a KeyError's quotes, OSError's errno)."""
    if isinstance(error, KeyError) and len(error.args) == 1:
        text = str(error.args[0])
    elif isinstance(error, OSError) and error.filename is not None and error.strerror:
        text = f"{error.filename}: {error.strerror.lower()}"
    else:
        text = str(error) or type(error).__name__
    return " ".join(text.split())  # one line


def command_line(command: str, prog: str | None = None) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Decorate a command's ``main(argv)`` so that bad input ends in one line and exit status 2 (see the module
    docstring); the decorated ``main`` returns what ``main`` returns (a console script's should be an exit status
    or None). The lines start with ``prog`` (default ``ekfslam-<command>``): give the parser's ``prog`` where it
    differs, so that argparse's own errors and the wrapper's read alike."""
    prog = prog or prog_name(command)

    def decorate(main: Callable[..., Any]) -> Callable[..., int]:
        @functools.wraps(main)
        def guarded(*args: Any, **kwargs: Any) -> Any:
            if debugging():
                return main(*args, **kwargs)
            try:
                return main(*args, **kwargs)
            except SystemExit as exit:  # sys.exit("message"): a message in place of a status is an error too
                if isinstance(exit.code, str):
                    print(f"{prog}: error: {exit.code}", file=sys.stderr)
                    raise SystemExit(USAGE_EXIT) from None
                raise
            except KeyboardInterrupt:
                print(f"{prog}: interrupted", file=sys.stderr)
                raise SystemExit(INTERRUPTED_EXIT) from None
            except _user_error_types() as error:
                print(f"{prog}: error: {error_message(error)}", file=sys.stderr)
                raise SystemExit(USAGE_EXIT) from None
            except Exception as error:  # a bug: say so in one line, and how to see where
                print(
                    f"{prog}: error: unexpected {type(error).__name__}: {error_message(error)} "
                    f"(set {DEBUG_ENV}=1 for the traceback)",
                    file=sys.stderr,
                )
                raise SystemExit(BUG_EXIT) from None

        return guarded

    return decorate


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


def merge_env_kwargs(
    trained: Mapping[str, Any] | None, overrides: Mapping[str, Any] | None
) -> dict[str, Any]:
    """A trained policy's recorded env settings with command-line ``--env-kwargs`` on top, section by section:
    ``{"filter": {"variant": "fej"}}`` changes the variant and keeps the rest of the record's ``filter``."""
    merged: dict[str, Any] = {
        key: dict(v) if isinstance(v, Mapping) else v for key, v in (trained or {}).items()
    }
    for key, value in (overrides or {}).items():
        if isinstance(value, Mapping) and isinstance(merged.get(key), Mapping):
            merged[key] = {**merged[key], **value}
        else:
            merged[key] = value
    return merged


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

"""The seed policy: which seeds are for what, and the checks every command line and trainer uses.

Every episode is seeded (``env.reset(seed=s)``), so a seed range names a fixed set of worlds. Four ranges:

- **held-out suite**, ``HELD_OUT_SEEDS`` (10000-10049): the final table only. Never train, tune or select a
  model on them; evaluate on them by name (``--seeds heldout``).
- **evaluation seeds**, from ``EVAL_SEED_START`` (20000 onwards): model selection during training (the first
  ``eval_episodes`` of them), sweeps (``SELECTION_SEEDS``, 20000-20009) and the default of ``evaluate``
  (``EVAL_SEEDS``, 20000-20049, as many as the held-out suite).
- **demonstration seeds**, from ``DEMONSTRATION_SEED_START`` (30000 onwards): the planners' demonstrations for
  behaviour cloning, kept clear of the two above.
- **training seeds**: everything else, the low seeds (0, 1, ... for the training envs, which ``make_vec_env``
  seeds ``seed`` to ``seed + n_envs - 1``).

Messages name a range through ``span`` (``"10000-10049"``), so a range changes in this file only.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

HELD_OUT_SEEDS: tuple[int, ...] = tuple(range(10000, 10050))
"""The held-out evaluation suite. Never train, tune or select models on these seeds."""

EVAL_SEED_START = 20000
"""The first evaluation seed: model selection (``eval_seed``), sweeps and the default of ``evaluate``."""

EVAL_SEEDS: tuple[int, ...] = tuple(range(EVAL_SEED_START, EVAL_SEED_START + len(HELD_OUT_SEEDS)))
"""The default seeds of ``evaluate``: evaluation seeds, as many as the held-out suite."""

SELECTION_EPISODES = 10
"""Evaluation episodes that select a model (a training run's default ``eval_episodes``; a sweep's seeds)."""

SELECTION_SEEDS: tuple[int, ...] = EVAL_SEEDS[:SELECTION_EPISODES]
"""The seeds a training run selects its best model on by default, and a sweep evaluates on."""

DEMONSTRATION_SEED_START = 30000
"""The first demonstration seed (behaviour cloning's default ``pretrain.seed``)."""

SUITES: dict[str, tuple[int, ...]] = {"heldout": HELD_OUT_SEEDS, "eval": EVAL_SEEDS}
"""Seed suites by name, as ``--seeds NAME`` takes them."""


def span(seeds: Sequence[int]) -> str:
    """``"A-B"`` for consecutive seeds, else them comma-separated (the form ``parse_seeds`` reads back)."""
    seeds = [int(s) for s in seeds]
    if seeds and seeds == list(range(seeds[0], seeds[0] + len(seeds))):
        return f"{seeds[0]}-{seeds[-1]}"
    return ",".join(map(str, seeds))


HELD_OUT = span(HELD_OUT_SEEDS)
"""``"10000-10049"``, for messages."""


def parse_seeds(text: str) -> list[int]:
    """A suite's name (``heldout``, ``eval``: ``SUITES``), ``A-B`` (inclusive), ``A,B,C``, or a mix such as
    ``0-4,10``; ValueError with the reason otherwise."""
    name = text.strip().lower().replace("-", "").replace("_", "")
    if name in SUITES:
        return list(SUITES[name])
    seeds: list[int] = []
    for part in filter(None, (p.strip() for p in text.split(","))):
        lo, _, hi = part.partition("-")
        try:
            first, last = int(lo), int(hi or lo)
        except ValueError:
            raise ValueError(
                f"seeds must look like A-B or A,B,C or name a suite ({', '.join(SUITES)}), got {text!r}"
            ) from None
        if last < first:
            raise ValueError(f"empty seed range {part!r}")
        seeds.extend(range(first, last + 1))
    if not seeds:
        raise ValueError(f"no seeds in {text!r}")
    return seeds


def suite_name(seeds: Sequence[int]) -> str | None:
    """The name of the suite ``seeds`` are (``heldout``, ``eval``), or None."""
    return next((name for name, suite in SUITES.items() if list(seeds) == list(suite)), None)


def held_out_overlap(seeds: Iterable[int]) -> list[int]:
    """The seeds of ``seeds`` that lie in the held-out suite, sorted (empty when none do)."""
    return sorted({int(s) for s in seeds} & set(HELD_OUT_SEEDS))


def check_not_held_out(seeds: Iterable[int], what: str) -> list[int]:
    """``seeds`` as a list; ValueError naming ``what`` (e.g. "evaluation seeds") if any is held out."""
    seeds = [int(s) for s in seeds]
    overlap = held_out_overlap(seeds)
    if overlap:
        raise ValueError(
            f"{what} {_some(overlap)} are in the held-out suite {HELD_OUT}, which is for the final table only; "
            f"use evaluation seeds ({EVAL_SEED_START} onwards) to select and compare models"
        )
    return seeds


def selection_seeds(first: int = EVAL_SEED_START, episodes: int = SELECTION_EPISODES) -> range:
    """The seeds a training run selects its model on: ``episodes`` of them from ``first`` (its ``eval_seed``)."""
    return range(int(first), int(first) + int(episodes))


def check_demonstration_seeds(seeds: Iterable[int], eval_seeds: Iterable[int] = SELECTION_SEEDS) -> list[int]:
    """``seeds`` as a list; ValueError if any is negative, in the held-out suite or among ``eval_seeds`` (the
    seeds that select the model the demonstrations teach)."""
    seeds = [int(s) for s in seeds]
    forbidden = set(HELD_OUT_SEEDS) | {int(s) for s in eval_seeds}
    bad = sorted({s for s in seeds if s < 0 or s in forbidden})
    if bad:
        raise ValueError(
            f"demonstration seeds {_some(bad)} are negative, in the held-out suite ({HELD_OUT}) or among the "
            f"evaluation seeds; pick a training range such as {DEMONSTRATION_SEED_START} onwards"
        )
    return seeds


def _some(seeds: Sequence[int]) -> str:
    """The first five of ``seeds``, with an ellipsis when there are more."""
    return f"{list(seeds[:5])}{'...' if len(seeds) > 5 else ''}"


# ------------------------------------------------------------------------------------ layout families
TRAINING_FAMILIES: tuple[str, ...] = ("arena", "pillars", "rooms", "loop", "figure_eight", "office")
"""The layout families (``ekfslam_gym.sim.families``) a generalist may be trained, tuned and selected on."""

HELDOUT_FAMILIES: tuple[str, ...] = ("warehouse", "maze")
"""Layout families for the final table only: never train, tune or select a model (nor tune a baseline) on
any world of them. ``maze`` is unlike every training family: corridors one cell wide that branch and end in
dead ends, a tree with no loop to close and no open space; ``warehouse`` (long aisles between rows of shelves
that hide all but one aisle) is held out as a second, nearer test."""


@dataclass(frozen=True)
class FamilySeeds:
    """One family's seed ranges: ``training`` (the training envs), ``evaluation`` (model selection, sweeps,
    comparisons) and ``heldout`` (the final table). A held-out family has no training or evaluation seeds."""

    training: range
    evaluation: tuple[int, ...]
    heldout: tuple[int, ...]


def family_seeds(family: str) -> FamilySeeds:
    """The seed ranges of one layout family: a training family's are the ranges above (seed s of two families
    names two different worlds); a held-out family has only the held-out suite. ValueError for an unknown one."""
    if family in TRAINING_FAMILIES:
        return FamilySeeds(range(0, min(HELD_OUT_SEEDS)), EVAL_SEEDS, HELD_OUT_SEEDS)
    if family in HELDOUT_FAMILIES:
        return FamilySeeds(range(0), (), HELD_OUT_SEEDS)
    raise ValueError(
        f"unknown layout family {family!r}; choose one of {', '.join(TRAINING_FAMILIES + HELDOUT_FAMILIES)}"
    )


def check_training_family(family: str, what: str) -> str:
    """``family``; ValueError naming ``what`` (e.g. "training envs") if it is a held-out family."""
    if family in HELDOUT_FAMILIES:
        raise ValueError(
            f"{what} use the held-out layout family {family!r}, which is for the final table only; train, "
            f"tune and select on the training families: {', '.join(TRAINING_FAMILIES)}"
        )
    return family

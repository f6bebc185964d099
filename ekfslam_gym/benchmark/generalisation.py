"""The generalisation suite: every baseline planner and every shipped policy on every v1 layout id, the
training families on their held-out seeds and the held-out families, IQM with 95 % bootstrap CIs.

The shipped generalist (``ppo EKFSLAM-Mix-v1``) was trained on the training families only; the other shipped
policies were each trained on one v0 id. Here they all run zero-shot (with the action interface and
observation settings they were trained with, on the v1 id's world, filter and horizon), which measures what
specialising on one layout costs on others. The cases:

- ``training family``: each training family's id (``EKFSLAM-v1`` is the arena family's, ``EKFSLAM-Loop-v1``
  the loop's) at its default tier, on that family's held-out seeds (``ekfslam_gym.seeds.family_seeds``);
- ``held-out family``: each held-out family's id at its default tier, on its seeds;
- ``large``: ``EKFSLAM-Large-v1`` on the held-out suite's seeds.

Every episode is one row of a CSV that the run appends to as it goes (``run(csv_path=...)`` skips the rows it
already holds, so a long run that was stopped resumes); the tables are made from the CSV alone. A ``--quick``
run takes one seed per case and cuts every episode to ``QUICK_EPISODE_TIME`` s: a check that everything runs,
not a result.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..evaluation.aggregate import aggregate
from ..evaluation.report import format_value

SUITE_METRICS: tuple[str, ...] = (
    "map_log_det",
    "landmark_rmse",
    "seen_fraction",
    "time_to_complete",
    "path_length",
    "collisions",
)
"""The table's columns, from ``ekfslam_gym.evaluation.episode_metrics`` (collisions: control steps in contact
with a wall, the wall contacts)."""

ARROWS = {
    "map_log_det": " ↓",
    "landmark_rmse": " ↓",
    "seen_fraction": " ↑",
    "time_to_complete": " ↓",
    "collisions": " ↓",
}
"""Which way is better, for the table's header (path length is neither: it is what the map cost)."""
SEEDS_PER_CASE = 50
"""Seeds per case in a full run: the first of each case's held-out seeds, all 50 of them, as the v0 benchmark
runs. At 10 a case, the frontier planner's landmark RMSE IQM on one training family's evaluation seeds ranged
over a factor of 2.2-2.8 from one draw of 10 seeds to another (5th to 95th percentile; ``docs/generalist.py
spread``): too wide to rank two agents by accuracy on one id."""
QUICK_EPISODE_TIME = 2.0
"""s of simulated time per episode in a ``--quick`` run (one seed per case)."""
LAYOUT_IDS: tuple[str, ...] = ("EKFSLAM-Large-v1",)
"""The v1 layout ids that are no family's (the family ids, ``EKFSLAM-v1`` and ``EKFSLAM-Loop-v1`` among them,
come from ``ekfslam_gym.sim.families``)."""
SPLITS: tuple[str, ...] = ("training family", "held-out family", "large")
ROW_KEYS: tuple[str, ...] = ("agent", "kind", "case", "split", "seed", "steps", "return", *SUITE_METRICS)


@dataclass(frozen=True)
class Case:
    """One env of the suite: the id, the tier (family ids; None for the layout ids), the split and seeds."""

    env_id: str
    tier: str | None
    split: str
    seeds: tuple[int, ...]

    @property
    def name(self) -> str:
        return self.env_id if self.tier is None else f"{self.env_id} ({self.tier})"

    def env_kwargs(self) -> dict[str, Any]:
        return {} if self.tier is None else {"tier": self.tier}


@dataclass(frozen=True)
class Contender:
    """An agent of the suite: its row label, ``baseline`` or ``shipped``, and a builder of (agent, the env
    settings it needs on top of the case's)."""

    label: str
    kind: str
    build: Callable[[], tuple[Any, Mapping[str, Any]]]


def cases(seeds_per_case: int = SEEDS_PER_CASE) -> list[Case]:
    """Every case of the suite, each with its first ``seeds_per_case`` held-out seeds: the family ids, then
    ``EKFSLAM-Large-v1``."""
    from ..seeds import HELD_OUT_SEEDS

    found = family_cases(seeds_per_case)
    found += [Case(env_id, None, "large", HELD_OUT_SEEDS[:seeds_per_case]) for env_id in LAYOUT_IDS]
    return found


def family_cases(seeds_per_case: int) -> list[Case]:
    """The family ids' cases at their default tier, training families first (``ekfslam_gym.seeds`` holds the
    split and each family's held-out seeds)."""
    from ..envs.presets import DEFAULT_TIER, family_id
    from ..seeds import HELDOUT_FAMILIES, TRAINING_FAMILIES, family_seeds

    found = []
    for split, families in (("training family", TRAINING_FAMILIES), ("held-out family", HELDOUT_FAMILIES)):
        for family in families:
            seeds = tuple(family_seeds(family).heldout)[:seeds_per_case]
            found.append(Case(family_id(family), DEFAULT_TIER, split, seeds))
    return found


def contenders() -> list[Contender]:
    """Every baseline planner (``ekfslam_gym.agents.BASELINES``), then every shipped policy."""
    from ..agents import BASELINES, make_agent
    from ..packaged import shipped_env_ids, shipped_model

    found = [Contender(name, "baseline", lambda name=name: (make_agent(name), {})) for name in BASELINES]

    def shipped(env_id: str) -> tuple[Any, Mapping[str, Any]]:
        agent = make_agent("ppo", model_path=shipped_model(env_id))
        return agent, zero_shot_settings(agent.trained_env_kwargs)

    for env_id in shipped_env_ids():
        found.append(Contender(f"ppo {env_id}", "shipped", lambda env_id=env_id: shipped(env_id)))
    return found


def zero_shot_settings(trained: Mapping[str, Any] | None) -> dict[str, Any]:
    """What a policy needs of its training settings on another id: its action interface and observation
    settings (so its input and output are what it learned on); its step limit and reward weights are left to
    the id (the horizon is the id's, the table's metrics do not read the reward)."""
    return {key: trained[key] for key in ("action", "observation") if trained and key in trained}


def _done(path: Path | None) -> set[tuple[str, str, int]]:
    if path is None or not path.is_file():
        return set()
    with path.open(newline="") as handle:
        return {(r["agent"], r["case"], int(r["seed"])) for r in csv.DictReader(handle)}


def run(
    suite: Sequence[Case],
    agents: Sequence[Contender],
    *,
    csv_path: Path | None = None,
    episode_time: float | None = None,
    progress: Callable[[str], None] | None = None,
) -> list[dict[str, Any]]:
    """Run every contender on every case's seeds; the episode rows (``ROW_KEYS``), each appended to
    ``csv_path`` as it finishes (rows the file already holds are not run again). Seed by seed: every contender
    on every case with its first seed, then with its second, ..., so that a run stopped early has as many
    seeds for every row of the table. ``episode_time`` (s) cuts every episode short (``--quick``)."""
    from ..evaluation.rollout import evaluate_agent

    done = _done(csv_path)
    built: dict[str, tuple[Any, Mapping[str, Any]]] = {}
    rows: list[dict[str, Any]] = []
    for index in range(max((len(case.seeds) for case in suite), default=0)):
        for case in suite:
            if index >= len(case.seeds):
                continue
            seed = case.seeds[index]
            for contender in agents:
                if (contender.label, case.name, seed) in done:
                    continue
                if contender.label not in built:
                    built[contender.label] = contender.build()
                agent, settings = built[contender.label]
                kwargs = {**settings, **case.env_kwargs()}
                if episode_time is not None:
                    kwargs["episode_time"] = episode_time
                (episode,) = evaluate_agent(agent, case.env_id, [seed], kwargs, label=contender.label)
                row = {"agent": contender.label, "kind": contender.kind, "case": case.name, "split": case.split,
                       **{key: episode[key] for key in ("seed", "steps", "return", *SUITE_METRICS)}}  # fmt: skip
                rows.append(row)
                if csv_path is not None:
                    _append(csv_path, row)
                if progress is not None:
                    progress(
                        f"{contender.label} on {case.name}, seed {seed}: seen {row['seen_fraction']:.2f}"
                    )
    return rows


def _append(path: Path, row: Mapping[str, Any]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    new = not path.is_file()
    with path.open("a", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=ROW_KEYS)
        if new:
            writer.writeheader()
        writer.writerow(row)


def read_rows(path: Path) -> list[dict[str, Any]]:
    """The episode rows of a suite's CSV, numbers as floats (seed and steps as ints)."""
    with path.open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    for row in rows:
        for key in ("return", *SUITE_METRICS):
            row[key] = float(row[key]) if row[key] not in ("", "nan") else math.nan
        row["seed"], row["steps"] = int(row["seed"]), int(row["steps"])
    return rows


def _ordered(values: Iterable[str]) -> list[str]:
    return list(dict.fromkeys(values))


def summarise(rows: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """``{"cases": {case: {agent: aggregate}}, "splits": {split: {agent: aggregate}}, "episodes": n}``: IQM,
    95 % bootstrap CI and mean of every ``SUITE_METRICS`` per case and agent, and over every episode of each
    split (``ekfslam_gym.evaluation.aggregate``)."""
    out: dict[str, Any] = {"cases": {}, "splits": {}, "episodes": len(rows)}
    for group, field in (("cases", "case"), ("splits", "split")):
        for name in _ordered(r[field] for r in rows):
            mine = [r for r in rows if r[field] == name]
            out[group][name] = {
                agent: {
                    "episodes": sum(r["agent"] == agent for r in mine),
                    "metrics": aggregate([r for r in mine if r["agent"] == agent], SUITE_METRICS),
                }
                for agent in _ordered(r["agent"] for r in mine)
            }
    return out


def _cell(metric: Mapping[str, Any]) -> str:
    if metric["iqm"] is None or not math.isfinite(metric["iqm"]):
        return "—"
    lo, hi = metric["ci"]
    return f"{format_value(metric['iqm'])} [{format_value(lo)}, {format_value(hi)}]"


def _table(by_agent: Mapping[str, Any], keys: Sequence[str] = SUITE_METRICS) -> list[str]:
    header = ["agent", "episodes", *(f"{k}{ARROWS.get(k, '')}" for k in keys)]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for agent, result in by_agent.items():
        cells = [agent, str(result["episodes"]), *(_cell(result["metrics"][k]) for k in keys)]
        lines.append("| " + " | ".join(cells) + " |")
    return lines


INTRO = (
    "Does a policy explore and close loops, or has it learned one layout? Every baseline planner and every "
    "shipped policy runs on worlds of every layout family: the training families on held-out seeds (worlds "
    "never trained on, of families a generalist may train on), the held-out families (warehouse, and maze, "
    "unlike every training family), and the Large rooms. `ppo EKFSLAM-Mix-v1` is the generalist, the "
    "policy shipped for every v1 layout id: trained on the training families only (`EKFSLAM-Mix-v1`), "
    "chosen on their evaluation seeds, and run here once. The other shipped policies are specialists, each "
    "trained on one v0 id: the gap between their rows and the planners' on worlds they never saw is what "
    "specialising costs. The first table pools every episode of a split; the tables by env follow."
)


def markdown(summary: Mapping[str, Any], *, about: str) -> str:
    """The suite's tables: one per split (every episode of it pooled), then one per case; ``about`` (the
    protocol: seeds, versions, command) goes under the title."""
    lines = ["# Generalisation", "", INTRO, "", about, "", "## By split", ""]
    for split, by_agent in summary["splits"].items():
        lines += [f"### {split}", "", *_table(by_agent), ""]
    lines += ["## By env", ""]
    for case, by_agent in summary["cases"].items():
        lines += [f"### `{case}`", "", *_table(by_agent), ""]
    return "\n".join(lines)


def about(rows: Sequence[Mapping[str, Any]], quick: bool, seeds_per_case: int) -> str:
    """The protocol paragraph of the page: seeds per case, horizon, versions, the command that made it."""
    from .. import __version__

    command = "ekfslam-benchmark --suite generalisation" + (" --quick" if quick else "")
    if seeds_per_case != (1 if quick else SEEDS_PER_CASE):
        command += f" --suite-seeds {seeds_per_case}"
    agents = _ordered(r["agent"] for r in rows)
    text = (
        f"Made by `{command} --out docs/results` in the project's repository (ekfslam-gym {__version__}, {len(rows)} "
        "episodes): "
        f"{seeds_per_case} held-out seed(s) per env, the first of each env's held-out seeds "
        f"(`ekfslam_gym.seeds`), {len(agents)} agents, every episode its id's full horizon at the default tier "
        "(medium); IQM [95 % bootstrap CI] over the episodes. The shipped policies, each trained on one v0 id or, "
        "the generalist (`ppo EKFSLAM-Mix-v1`), on the training families' mix, run zero-shot with the action "
        "interface and observation settings they were trained with. "
        "`time_to_complete` is the simulated time (s) until every landmark's sigma was below `done_std` (the "
        "episode's length if never); `collisions` counts control steps in contact with a wall; `path_length` "
        "is in m. Per-episode rows: `generalisation.csv`."
    )
    if quick:
        text += (f"\n\n**A quick run**: each episode cut to {QUICK_EPISODE_TIME} s. A check that the suite runs, "
                 "not a result.")  # fmt: skip
    return text


def run_suite(
    *,
    quick: bool = False,
    seeds_per_case: int | None = None,
    out: Path | None = None,
    progress: Callable[[str], None] | None = None,
) -> str:
    """The whole suite with ``seeds_per_case`` seeds per case (default ``SEEDS_PER_CASE``; ``--quick``: one
    seed, short episodes): runs what ``out/generalisation.csv`` does not hold yet, writes ``generalisation.md``
    and ``generalisation.json`` beside it from the CSV's rows of these seeds, and returns the Markdown."""
    import json

    from ..evaluation.report import json_safe

    if seeds_per_case is None:
        seeds_per_case = 1 if quick else SEEDS_PER_CASE
    if seeds_per_case < 1:
        raise ValueError(f"seeds_per_case must be >= 1, got {seeds_per_case}")
    suite = cases(seeds_per_case)
    csv_path = None if out is None else Path(out) / "generalisation.csv"
    rows = run(suite, contenders(), csv_path=csv_path, episode_time=QUICK_EPISODE_TIME if quick else None,
               progress=progress)  # fmt: skip
    if csv_path is not None:
        wanted = {(c.name, seed) for c in suite for seed in c.seeds}
        rows = [r for r in read_rows(csv_path) if (r["case"], r["seed"]) in wanted]
    summary = summarise(rows)
    text = markdown(summary, about=about(rows, quick, seeds_per_case))
    if out is not None:
        Path(out, "generalisation.md").write_text(text)
        Path(out, "generalisation.json").write_text(json.dumps(json_safe(summary), indent=1, allow_nan=False))
    return text

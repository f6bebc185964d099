"""The generalist's learning curves against wall-clock time (docs/generalist.md): every checkpoint of a training
run evaluated on EKFSLAM-v1's evaluation seeds, beside the greedy and frontier planners on the same seeds.

    python docs/generalist.py curve RUN [RUN ...] [--cpu-log FILE] [--seeds 20000-20009]   # evaluate, then plot
    python docs/generalist.py plot                                                       # from the CSV only
    python docs/generalist.py spread [--seeds 20000-20049]     # how far 10 seeds can move a landmark RMSE IQM
    python docs/generalist.py interfaces [--seeds 20000-20049] # one planner through every action interface

A checkpoint's wall-clock time is its file's modification time less the run's start (the ``t_start`` of its monitor
files); for a run continued with ``--resume``, the time of the checkpoint it resumed from plus the time since it
resumed, so that the pause between is not counted. With ``--cpu-log`` (lines ``<epoch> <pid>:<cpu-seconds> ...``,
sampled while the runs trained, and ``--pid RUN=PID``, the process of the run's last part), the run's own CPU time
at that moment is interpolated too, added to that of the checkpoint a resumed part started from: on two cores shared
by four runs, the wall-clock time is an upper bound and the CPU time is what one core alone would have taken.
Evaluation seeds only (``ekfslam_gym.seeds.EVAL_SEEDS``): a figure for reporting, never for selecting.

``spread`` runs the generalist and the frontier planner on every training family's evaluation seeds and asks how
much one draw of 10 of those seeds (the generalisation suite's size in 0.3.0) moves a landmark RMSE IQM, and so
how often 10 seeds rank the two agents the way all of them do (the episodes are cached in
``docs/data/generalist_spread.csv``).

``interfaces`` runs the one nearest-frontier planner through each action interface (velocity, primitives, the
teacher's primitives growing the map outwards, primitives held 3 control steps, waypoints) and the generalist on
the same evaluation seeds, and tables each one's map log det, landmark RMSE, the RMSE its own filter expects
(sqrt of the mean of tr Sigma_jj over the seen landmarks, at the end) and path length (episodes cached in
``docs/data/generalist_interfaces.csv``).
"""

from __future__ import annotations

import argparse
import csv
import json
import re
import sys
from pathlib import Path

import numpy as np

DOCS = Path(__file__).resolve().parent
CSV = DOCS / "data" / "generalist_curve.csv"
PNG = DOCS / "generalist_curve.png"
ENV_ID = "EKFSLAM-v1"
PLANNERS = ("greedy", "frontier")
SPREAD_CSV = DOCS / "data" / "generalist_spread.csv"
SPREAD_FIELDS = ("agent", "family", "seed", "map_log_det", "landmark_rmse")
SPREAD_AGENTS = ("generalist", "frontier")
FIELDS = ("run", "steps", "wall_s", "cpu_s", "map_log_det", "lo", "hi", "landmark_rmse")
CHECKPOINT = re.compile(r"ppo_(\d+)_steps\.zip")
# runs/gen/<kind>_s<seed>, as the research log's commands name them
RUN_NAME = re.compile(r"(scratch|scratchnopv|scratche5|scratchent|bc)_s(\d+)")
KINDS = {
    "scratch": "from scratch",
    "scratchnopv": "from scratch, no pose-variance charge",
    "scratche5": "from scratch, 5 epochs an update",
    "scratchent": "from scratch, entropy bonus 0.01",
    "bc": "the recipe: cloned, then PPO",
}


def legend(run: str) -> str:
    """``scratch_s0`` -> "from scratch, seed 0"; other names as they are."""
    match = RUN_NAME.fullmatch(run)
    return f"{KINDS[match.group(1)]}, seed {match.group(2)}" if match else run


def first_start(folder: Path) -> float:
    """The earliest ``t_start`` of the monitor files under ``folder``, epoch seconds."""
    starts = []
    for path in folder.rglob("*.monitor.csv"):
        with path.open() as handle:
            starts.append(json.loads(handle.readline().lstrip("#"))["t_start"])
    if not starts:
        raise SystemExit(f"{folder}: no monitor files, so no start time")
    return min(starts)


def run_starts(run: Path) -> dict[int, float]:
    """When each part of a run started, by the step count it started from: ``{0: start}``, plus one entry per
    ``--resume`` (a resumed part writes its monitor files to ``monitor/from_<steps>``)."""
    starts = {int(folder.name.removeprefix("from_")): first_start(folder)
              for folder in (run / "monitor").glob("from_*")}  # fmt: skip
    if 0 not in starts:
        raise SystemExit(f"{run}: no monitor/from_0, so no start time")
    return starts


def part_of(starts: dict[int, float], steps: int) -> int:
    """The step count the part of a run that wrote the checkpoint at ``steps`` started from (``run_starts``'s
    keys): a checkpoint a part resumed from was written by the part before it."""
    return max((start for start in starts if start < steps), default=0)


def cpu_at(log: Path, pid: int, when: float) -> float:
    """The CPU seconds of process ``pid`` at epoch ``when``, interpolated in the sampler's log."""
    times, cpu = [], []
    for line in log.read_text().splitlines():
        stamp, *fields = line.split()
        for field in fields:
            owner, _, seconds = field.partition(":")
            if int(owner) == pid:
                times.append(float(stamp))
                cpu.append(float(seconds))
    if not times:
        return float("nan")
    return float(np.interp(when, times, cpu))


def evaluate(agent, seeds: list[int], settings: dict) -> dict[str, float]:
    """IQM [95 % CI] of the map log det and IQM landmark RMSE of ``agent`` on ``ENV_ID``'s ``seeds``."""
    from ekfslam_gym.evaluation.aggregate import aggregate
    from ekfslam_gym.evaluation.rollout import evaluate_agent

    episodes = evaluate_agent(agent, ENV_ID, seeds, settings)
    result = aggregate(episodes, ("map_log_det", "landmark_rmse"))
    lo, hi = result["map_log_det"]["ci"]
    return {
        "map_log_det": result["map_log_det"]["iqm"],
        "lo": lo,
        "hi": hi,
        "landmark_rmse": result["landmark_rmse"]["iqm"],
    }


def curve(runs: list[Path], seeds: list[int], cpu_log: Path | None, pids: dict[str, int]) -> list[dict]:
    """One row per checkpoint of every run (its clone, for a cloned run, at 0 steps) and one per planner."""
    from ekfslam_gym.agents import make_agent

    from ekfslam_gym.benchmark.generalisation import zero_shot_settings

    done = {
        (r["run"], r["steps"]): r for r in read()
    }  # rows of an earlier call are kept, not evaluated again
    rows = []
    for name in PLANNERS:
        if (name, "") in done:
            rows.append(done[(name, "")])
            continue
        rows.append({"run": name, "steps": "", "wall_s": "", "cpu_s": "",
                     **evaluate(make_agent(name), seeds, {})})  # fmt: skip
        print(f"{name}: {rows[-1]['map_log_det']:.1f}", file=sys.stderr)
    for run in runs:
        starts = run_starts(run)
        clock: dict[int, tuple[float, float]] = {}  # steps -> (wall s, CPU s) since the run began
        models = [(0, run / "bc_model.zip")] if (run / "bc_model.zip").is_file() else []
        models += sorted(
            (int(m.group(1)), path)
            for path in (run / "checkpoints").glob("ppo_*_steps.zip")
            if (m := CHECKPOINT.fullmatch(path.name))
        )
        for steps, path in models:
            if (run.name, str(steps)) in done:
                rows.append(done[(run.name, str(steps))])
                clock[steps] = (float(rows[-1]["wall_s"]), float(rows[-1]["cpu_s"] or "nan"))
                continue
            origin = part_of(starts, steps)
            if origin and origin not in clock:
                raise SystemExit(f"{run}: resumed from {origin} steps, but that checkpoint is missing")
            wall0, cpu0 = clock[origin] if origin else (0.0, 0.0)
            agent = make_agent("ppo", model_path=path)
            stamp = path.stat().st_mtime
            pid = pids.get(run.name)
            cpu = cpu_at(cpu_log, pid, stamp) if cpu_log is not None and pid is not None else float("nan")
            clock[steps] = (wall0 + stamp - starts[origin], cpu0 + cpu)
            rows.append({"run": run.name, "steps": steps, "wall_s": round(clock[steps][0], 1),
                         "cpu_s": round(clock[steps][1], 1),
                         **evaluate(agent, seeds, zero_shot_settings(agent.trained_env_kwargs))})  # fmt: skip
            print(f"{run.name} {steps}: {rows[-1]['map_log_det']:.1f}", file=sys.stderr)
    return rows


def read() -> list[dict]:
    """The CSV's rows as written (strings), or none."""
    if not CSV.is_file():
        return []
    with CSV.open(newline="") as handle:
        return list(csv.DictReader(handle))


def write(rows: list[dict]) -> None:
    CSV.parent.mkdir(parents=True, exist_ok=True)
    with CSV.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=FIELDS)
        writer.writeheader()
        for row in rows:
            writer.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in row.items()})


def plot() -> None:
    """docs/generalist_curve.png from the CSV: map log det against minutes, one line per run: the runs' CPU
    time where the CSV has it for every checkpoint, else their wall-clock time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = read()
    fig, ax = plt.subplots(figsize=(8, 5))
    trained = [r for r in rows if r["steps"]]
    clock = "cpu_s" if all(np.isfinite(float(r["cpu_s"])) for r in trained) else "wall_s"
    for name in dict.fromkeys(r["run"] for r in trained):
        mine = [r for r in rows if r["run"] == name]
        minutes = np.array([float(r[clock]) for r in mine]) / 60
        iqm = np.array([float(r["map_log_det"]) for r in mine])
        lo = np.array([float(r["lo"]) for r in mine])
        hi = np.array([float(r["hi"]) for r in mine])
        (line,) = ax.plot(minutes, iqm, marker="o", markersize=3, label=legend(name))
        ax.fill_between(minutes, lo, hi, color=line.get_color(), alpha=0.15)
    for style, name in zip(("--", ":"), PLANNERS):
        level = next(float(r["map_log_det"]) for r in rows if r["run"] == name)
        ax.axhline(level, color="black", linestyle=style, linewidth=1, label=f"{name} planner")
    ax.axvline(30, color="grey", linewidth=0.8, label="30 min")
    ax.set_xlabel(
        "minutes of the run's CPU time (its wall clock alone on one core)"
        if clock == "cpu_s"
        else "wall-clock minutes since the run started"
    )
    ax.set_ylabel(f"map log det on {ENV_ID} ↓\n(IQM, 95 % CI, evaluation seeds)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(PNG, dpi=110)
    print(PNG)


def draws_of(
    values: dict[str, np.ndarray], size: int, draws: int, rng: np.random.Generator
) -> dict[str, np.ndarray]:
    """The IQM of each agent's ``values`` (one per seed, the same seeds in the same order for every agent) over
    ``draws`` random subsets of ``size`` seeds, the same subsets for every agent: one array of ``draws`` each."""
    from ekfslam_gym.evaluation.metrics import iqm

    count = len(next(iter(values.values())))
    picks = np.array([rng.choice(count, size, replace=False) for _ in range(draws)])
    return {agent: np.array([iqm(draw) for draw in np.asarray(v)[picks]]) for agent, v in values.items()}


def cached_episodes(path: Path) -> dict[tuple[str, str, int], dict]:
    """The episodes cached in ``path``, by (agent, family, seed); none when it does not exist yet."""
    if not path.is_file():
        return {}
    with path.open(newline="") as handle:
        return {(r["agent"], r["family"], int(r["seed"])): r for r in csv.DictReader(handle)}


def write_episodes(path: Path, fields: tuple[str, ...], rows: list[dict]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=fields)
        writer.writeheader()
        writer.writerows(rows)


def shipped_generalist():
    """The shipped generalist and the env settings it runs a v1 id in (its own action interface)."""
    from ekfslam_gym.agents import make_agent

    from ekfslam_gym.benchmark.generalisation import zero_shot_settings
    from ekfslam_gym.pretrained import shipped_policy_file

    agent = make_agent("ppo", model_path=shipped_policy_file("EKFSLAM-Mix-v1"))
    return agent, zero_shot_settings(agent.trained_env_kwargs)


def spread_episodes(seeds: list[int]) -> list[dict]:
    """Every (agent, training family, seed) episode's map log det and landmark RMSE: the cached rows, and those
    missing run now (the family's id at its default tier)."""
    from ekfslam_gym.agents import make_agent

    from ekfslam_gym.envs.presets import family_id
    from ekfslam_gym.evaluation.rollout import evaluate_agent
    from ekfslam_gym.seeds import TRAINING_FAMILIES

    have = cached_episodes(SPREAD_CSV)
    rows = []
    for name in SPREAD_AGENTS:
        agent, settings = shipped_generalist() if name == "generalist" else (make_agent(name), {})
        for family in TRAINING_FAMILIES:
            missing = [seed for seed in seeds if (name, family, seed) not in have]
            episodes = evaluate_agent(agent, family_id(family), missing, settings) if missing else []
            for seed, episode in zip(missing, episodes):
                have[(name, family, seed)] = {"agent": name, "family": family, "seed": seed,
                                              **{k: episode[k] for k in SPREAD_FIELDS[3:]}}  # fmt: skip
            rows += [have[(name, family, seed)] for seed in seeds]
            print(f"{name} {family}: {len(missing)} run, {len(seeds) - len(missing)} cached", file=sys.stderr)
    write_episodes(SPREAD_CSV, SPREAD_FIELDS, rows)
    return rows


def spread(rows: list[dict], size: int = 10, draws: int = 2000, seed: int = 0) -> str:
    """The Markdown table of ``spread``: per training family, each agent's landmark RMSE IQM over all its seeds,
    the frontier's over draws of ``size`` seeds (5th-95th percentile), and the share of draws in which the
    generalist's is at or below the frontier's, on that family and on every family at once."""
    from ekfslam_gym.evaluation.metrics import iqm

    rng = np.random.default_rng(seed)
    families = list(dict.fromkeys(r["family"] for r in rows))
    lines = [
        f"| family | generalist, all {{n}} seeds | frontier, all {{n}} | frontier, {size} seeds (5-95 %) | "
        f"generalist at or below, {size} seeds |",
        "|---|---|---|---|---|",
    ]
    every = np.ones(draws, dtype=bool)
    for family in families:
        values = {}
        for agent in SPREAD_AGENTS:
            mine = sorted((int(r["seed"]), float(r["landmark_rmse"])) for r in rows
                          if r["agent"] == agent and r["family"] == family)  # fmt: skip
            values[agent] = np.array([v for _, v in mine])
        drawn = draws_of(values, size, draws, rng)
        below = drawn["generalist"] <= drawn["frontier"]
        every &= below
        lo, hi = np.percentile(drawn["frontier"], [5, 95])
        lines.append(f"| {family} | {iqm(values['generalist']):.3f} | {iqm(values['frontier']):.3f} | "
                     f"{lo:.3f}-{hi:.3f} | {below.mean():.0%} |")  # fmt: skip
    lines.append(f"| every family at once | | | | {every.mean():.1%} |")
    count = len(values["frontier"])
    return "\n".join(lines).replace("{n}", str(count)) + "\n"


INTERFACES_CSV = DOCS / "data" / "generalist_interfaces.csv"
INTERFACE_FIELDS = ("agent", "family", "seed", "map_log_det", "landmark_rmse", "expected_rmse", "path_length")
# (label, agent name, its arguments, the action settings it runs in); the generalist runs in its own.
INTERFACE_AGENTS = (
    ("frontier, velocity", "frontier", {}, {}),
    ("frontier, primitives", "frontier-primitives", {}, {"kind": "primitives"}),
    ("frontier, primitives, growing outwards (the teacher)", "frontier-primitives", {"home_weight": 0.5},
     {"kind": "primitives"}),
    ("frontier, primitives held 3 steps", "frontier-primitives", {}, {"kind": "primitives", "hold": 3}),
    ("frontier, waypoints", "frontier-waypoint", {}, {"kind": "waypoint"}),
    ("generalist", "ppo", {}, None),
)  # fmt: skip


def expected_rmse(env) -> float:
    """The landmark RMSE the filter of ``env`` (at the end of an episode) expects: sqrt of the mean of
    tr Sigma_jj over the seen landmarks, what the map's marginal covariances predict, correlations left out."""
    ekf = env.unwrapped.filter
    seen = np.flatnonzero(np.asarray(ekf.observed))
    if seen.size == 0:
        return float("nan")
    diagonal = np.diag(np.asarray(ekf.cov))[3:].reshape(-1, 2)
    return float(np.sqrt(diagonal[seen].sum(axis=1).mean()))


def interface_episodes(seeds: list[int]) -> list[dict]:
    """Every (agent, training family, seed) episode of ``INTERFACE_AGENTS``: the cached rows, and those missing
    run now (the family's id at its default tier)."""
    from ekfslam_gym.agents import make_agent

    from ekfslam_gym.envs.presets import family_id
    from ekfslam_gym.evaluation.rollout import make_env, run_episode
    from ekfslam_gym.seeds import TRAINING_FAMILIES

    have = cached_episodes(INTERFACES_CSV)
    rows = []
    for label, name, kwargs, action in INTERFACE_AGENTS:
        if name == "ppo":
            agent, settings = shipped_generalist()
        else:
            agent, settings = make_agent(name, **kwargs), ({"action": action} if action else {})
        for family in TRAINING_FAMILIES:
            missing = [seed for seed in seeds if (label, family, seed) not in have]
            if missing:
                env = make_env(family_id(family), settings)
                for seed in missing:
                    episode = run_episode(env, agent, seed)
                    have[(label, family, seed)] = {
                        "agent": label, "family": family, "seed": seed, "map_log_det": episode["map_log_det"],
                        "landmark_rmse": episode["landmark_rmse"], "expected_rmse": expected_rmse(env),
                        "path_length": episode["path_length"],
                    }  # fmt: skip
                env.close()
            rows += [have[(label, family, seed)] for seed in seeds]
            print(
                f"{label} {family}: {len(missing)} run, {len(seeds) - len(missing)} cached", file=sys.stderr
            )
    write_episodes(INTERFACES_CSV, INTERFACE_FIELDS, rows)
    return rows


def interfaces(rows: list[dict]) -> str:
    """The Markdown table of ``interfaces``: per agent and training family, IQM of the map log det / landmark
    RMSE / the RMSE the filter expects, and the median path length (m)."""
    from ekfslam_gym.evaluation.metrics import iqm

    families = list(dict.fromkeys(r["family"] for r in rows))
    agents = list(dict.fromkeys(r["agent"] for r in rows))
    lines = ["| agent | " + " | ".join(f.replace("_", " ") for f in families) + " |",
             "|---|" + "---|" * len(families)]  # fmt: skip
    for agent in agents:
        cells = []
        for family in families:
            mine = [r for r in rows if r["agent"] == agent and r["family"] == family]
            value = {k: np.array([float(r[k]) for r in mine]) for k in INTERFACE_FIELDS[3:]}
            cells.append(f"{iqm(value['map_log_det']):.1f} / {iqm(value['landmark_rmse']):.3f} / "
                         f"{iqm(value['expected_rmse']):.3f} / {np.median(value['path_length']):.0f}")  # fmt: skip
        lines.append(f"| {agent} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    make = sub.add_parser("curve", help="evaluate every checkpoint of the runs, write the CSV, plot")
    make.add_argument("runs", nargs="+", type=Path)
    make.add_argument("--seeds", default="20000-20009")
    make.add_argument("--cpu-log", type=Path)
    make.add_argument("--pid", action="append", default=[], metavar="RUN=PID")
    sub.add_parser("plot", help="plot the CSV")
    spreading = sub.add_parser("spread", help="how much 10 seeds move a landmark RMSE IQM")
    spreading.add_argument("--seeds", default="20000-20049")
    interfacing = sub.add_parser(
        "interfaces", help="one planner through every action interface, and the generalist"
    )
    interfacing.add_argument("--seeds", default="20000-20049")
    args = parser.parse_args(argv)
    if args.command in ("curve", "spread", "interfaces"):
        import torch

        from ekfslam_gym.seeds import check_not_held_out, parse_seeds

        torch.set_num_threads(1)
        seeds = check_not_held_out(parse_seeds(args.seeds), f"the {args.command}'s seeds")
    if args.command == "spread":
        print(spread(spread_episodes(seeds)), end="")
        return 0
    if args.command == "interfaces":
        print(interfaces(interface_episodes(seeds)), end="")
        return 0
    if args.command == "curve":
        pids = {name: int(pid) for name, _, pid in (p.partition("=") for p in args.pid)}
        write(curve(args.runs, seeds, args.cpu_log, pids))
    plot()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""The standard protocol in one place: an agent on the held-out suite of each registered env, scored by the IQM
with a 95 % bootstrap CI of every episode metric, beside the reference rows.

The **reference rows** (``reference.json`` in this package) are the baselines and the shipped policies from the
last full runs on the held-out suite, copied from ``docs/results.md`` with each row's source (line and commit)
and the versions that made them; the README's held-out tables are generated from them (``reference_table``).
A ``--quick`` run uses the suite's first ``QUICK_EPISODES`` seeds: a smoke test, not a result.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from functools import cache
from importlib import resources
from typing import Any

from ..evaluation.aggregate import summary
from ..evaluation.episode_metrics import METRIC_KEYS
from ..evaluation.report import format_value, json_safe
from ..seeds import HELD_OUT_SEEDS, span

QUICK_EPISODES = 5
TABLE_KEYS: tuple[str, ...] = (
    "map_log_det",
    "landmark_rmse",
    "seen_fraction",
    "ate",
    "loop_closures",
    "collisions",
)
"""The columns of the Markdown table (the JSON holds every metric); the reference rows of the shipped Large
policy hold only some metrics, shown as a dash elsewhere."""


@cache
def reference() -> dict[str, Any]:
    """``reference.json``: ``{"about", "protocol", "package", "versions", "envs": {env_id: [row, ...]}}``, each row
    ``{"agent", "label", "kind" (baseline | shipped), "episodes", "metrics": {key: {"iqm", "ci"}}, "source"}``, and
    ``"package"`` where a row was made by another version of the package than the file's ``package`` names."""
    return json.loads(resources.files(__name__).joinpath("reference.json").read_text(encoding="utf-8"))


def reference_rows(env_id: str) -> list[dict[str, Any]]:
    """The reference rows of ``env_id`` (empty for an env without any)."""
    return list(reference()["envs"].get(env_id.split(":")[-1], []))


def protocol_seeds(quick: bool = False) -> tuple[int, ...]:
    """The held-out suite, or its first ``QUICK_EPISODES`` seeds for a quick run."""
    return HELD_OUT_SEEDS[:QUICK_EPISODES] if quick else HELD_OUT_SEEDS


def run(
    make: Callable[[str], tuple[Any, Mapping[str, Any] | None]],
    env_ids: Sequence[str],
    label: str,
    *,
    quick: bool = False,
    progress: bool = False,
) -> dict[str, Any]:
    """Run the agent ``make(env_id)`` builds (with the env settings it needs, None for the id's own) on each env's
    protocol seeds; the report: ``{"agent", "quick", "seeds", "package", "results": {env_id: {"summary",
    "reference", "reproduces"}}}`` (``reproduces``: for an agent with a reference row of its own name, whether
    each shared metric prints as that row does, IQM and CI ends, at the table's precision)."""
    # the episode loop here, not at import: its imports would slow ekfslam-benchmark --help
    from .. import __version__
    from ..evaluation.rollout import evaluate_agent

    seeds = protocol_seeds(quick)
    results: dict[str, Any] = {}
    for env_id in env_ids:
        agent, env_kwargs = make(env_id)
        episodes = evaluate_agent(agent, env_id, seeds, env_kwargs, label=label, progress=progress)
        result = summary(label, episodes, keys=METRIC_KEYS)
        own = [r for r in reference_rows(env_id) if r["agent"] == label]
        results[env_id] = {
            "summary": result,
            "reference": reference_rows(env_id),
            "reproduces": None if quick or not own else reproduces(result, own[0]),
        }
    return json_safe(
        {"agent": label, "quick": quick, "seeds": span(seeds), "package": __version__, "results": results}
    )


def _cell(metric: Mapping[str, Any] | None) -> str:
    if metric is None or metric.get("iqm") is None:
        return "—"
    lo, hi = (float("nan") if v is None else v for v in metric["ci"])
    return f"{format_value(metric['iqm'])} [{format_value(lo)}, {format_value(hi)}]"


def reference_note(env_id: str, quick: bool = False) -> str:
    """Which package made the reference rows, from where, and whether a run's row can be read against them."""
    package = reference()["package"]
    sources = sorted({f"{r['source']['file']} at {r['source']['commit']}" for r in reference_rows(env_id)})
    comparable = (
        "not comparable with this --quick run (5 of the 50 seeds)"
        if quick
        else f"comparable: {package['comparable']}"
    )
    made = " and ".join(sorted({r.get("package", package["ekfslam-gym"]) for r in reference_rows(env_id)}))
    return (
        f"Reference rows: made by ekfslam-gym {made} on {env_id.split(':')[-1]}, from "
        f"{'; '.join(sources)} (ekfslam_gym/benchmark/reference.json); {comparable}.\n"
    )


def reproduces(result: Mapping[str, Any], row: Mapping[str, Any]) -> dict[str, bool]:
    """Per metric the two share: whether ``result`` prints as the reference ``row`` (IQM and CI)."""
    return {
        key: _cell(result["metrics"].get(key)) == _cell(metric)
        for key, metric in row["metrics"].items()
        if key in result["metrics"]
    }


def _table(rows: Sequence[tuple[str, Mapping[str, Any]]], keys: Sequence[str]) -> str:
    header = ["agent", "episodes", *keys]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for label, row in rows:
        cells = [label, str(row["episodes"]), *(_cell(row["metrics"].get(k)) for k in keys)]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def reference_table(env_id: str, keys: Sequence[str] = TABLE_KEYS) -> str:
    """The reference rows of ``env_id`` as a Markdown table (what the README shows)."""
    return _table([(r["label"], r) for r in reference_rows(env_id)], keys)


def markdown(report: Mapping[str, Any], keys: Sequence[str] = TABLE_KEYS) -> str:
    """One section per env: this run's row first, then the reference rows, with the protocol and sources."""
    parts = []
    quick = " (--quick: a smoke test, not comparable with the reference rows)" if report["quick"] else ""
    for env_id, result in report["results"].items():
        this = result["summary"]
        rows = [(f"**{report['agent']}** (this run)", this)]
        rows += [(f"{r['label']} (reference)", r) for r in result["reference"]]
        text = [f"## `{env_id}`\n\nHeld-out seeds {report['seeds']}{quick}, IQM [95 % bootstrap CI]; "
                f"ekfslam-gym {report['package']}.\n\n" + _table(rows, keys)]  # fmt: skip
        if result["reproduces"] is not None:
            differ = [k for k, same in result["reproduces"].items() if not same]
            agreed = len(result["reproduces"]) - len(differ)
            text.append(f"Against its reference row: {agreed} of {len(result['reproduces'])} metrics print the "
                        f"same{'' if not differ else '; differ: ' + ', '.join(differ)}.\n")  # fmt: skip
        if result["reference"]:
            text.append(reference_note(env_id, quick=report["quick"]))
        parts.append("\n".join(text))
    return "\n".join(parts)

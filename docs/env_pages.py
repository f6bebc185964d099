"""One page per registered env id, in the shape of Gymnasium's and Minigrid's env pages (used by generate.py).

Every id the package registers at build time gets its page, so a new id is documented by registering it:

- a header table (action space, observation space, reward range, episode length, the import line);
- the description (from ``EKFSLAMEnv``'s docstring), a picture of the env's own frame with its legend;
- the headline results (the reference rows of ``ekfslam_gym.benchmark``: the best baseline and the shipped
  policy, the five metrics that matter) and a link to every metric;
- the full configuration the id builds, every field written out;
- the shipped policy, if there is one, and the version history (``ekfslam_gym.envs.presets.VERSION_HISTORY``: a registered
  version without an entry there stops the generator).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
GIF_ENV = "EKFSLAM-Maze-v1"  # the generalist's GIF (docs/ppo_EKFSLAM-Mix-v1.gif): a held-out family
# The five numbers that say how good a run was (Evaluation protocol defines each), best first in the table.
HEADLINE = (
    ("map_log_det", "map log det Σ ↓"),
    ("landmark_rmse", "landmark RMSE (m) ↓"),
    ("ate", "ATE (m) ↓"),
    ("seen_fraction", "fraction seen ↑"),
    ("collisions", "collisions ↓"),
)


def registered_ids() -> list[str]:
    """Every env id this package registers, in registration order."""
    from gymnasium.envs.registration import registry

    import ekfslam_gym  # noqa: F401  (registers the ids)

    return [
        env_id
        for env_id, spec in registry.items()
        if isinstance(spec.entry_point, str) and spec.entry_point.startswith("ekfslam_gym.")
    ]


def family(env_id: str) -> tuple[str, int]:
    """("EKFSLAM-Large", 0) for "EKFSLAM-Large-v0"."""
    match = re.fullmatch(r"(.+)-v(\d+)", env_id)
    if not match:
        raise ValueError(f"env id {env_id!r} has no version suffix -vN")
    return match.group(1), int(match.group(2))


def version_history(env_id: str) -> list[dict[str, Any]]:
    """The releases of ``env_id``'s family, oldest first (``ekfslam_gym.envs.presets.VERSION_HISTORY``, the one
    source); every registered version of it must have one."""
    from ekfslam_gym.envs.presets import VERSION_HISTORY

    name, _ = family(env_id)
    entries = [
        {"version": int(release.version.lstrip("v")), "package": release.package, "change": release.changes}
        for release in VERSION_HISTORY.get(name, ())
    ]
    known = {f"{name}-v{entry['version']}" for entry in entries}
    registered = {i for i in registered_ids() if family(i)[0] == name}
    missing = sorted(registered - known)
    if missing:
        raise SystemExit(f"ekfslam_gym.envs.presets.VERSION_HISTORY: add a release for {missing}")
    return sorted(entries, key=lambda e: e["version"])


def _value(metric: dict[str, Any] | None) -> str:
    from ekfslam_gym.evaluation.report import format_value

    if metric is None:
        return "not recorded"
    low, high = metric["ci"]
    return f"{format_value(metric['iqm'])} [{format_value(low)}, {format_value(high)}]"


def headline_rows(env_id: str) -> list[tuple[str, dict[str, Any]]]:
    """(label, reference row) of the baseline with the lowest map log det and of each shipped policy."""
    from ekfslam_gym.benchmark import reference_rows

    rows = reference_rows(env_id)
    baselines = [r for r in rows if r["kind"] == "baseline" and "map_log_det" in r["metrics"]]
    chosen = []
    if baselines:
        best = min(baselines, key=lambda r: r["metrics"]["map_log_det"]["iqm"])
        chosen.append((f"{best['agent']} (best baseline)", best))
    chosen += [("shipped policy", r) for r in rows if r["kind"] == "shipped"]
    return chosen


def headline_table(env_id: str, every_agent: bool = False) -> list[str]:
    """The headline results as Markdown lines (empty without reference rows): the best baseline and the shipped
    policy, or ``every_agent``'s rows."""
    from ekfslam_gym.benchmark import reference_rows

    if every_agent:
        rows = [
            ("shipped policy" if r["kind"] == "shipped" else r["agent"], r) for r in reference_rows(env_id)
        ]
    else:
        rows = headline_rows(env_id)
    if not rows:
        return []
    lines = [
        "| agent | " + " | ".join(label for _, label in HEADLINE) + " |",
        "|---|" + "---|" * len(HEADLINE),
    ]
    for label, row in rows:
        lines.append(f"| {label} | " + " | ".join(_value(row["metrics"].get(k)) for k, _ in HEADLINE) + " |")
    return lines


def _yaml(data: Any) -> str:
    import yaml

    return yaml.safe_dump(data, sort_keys=False, allow_unicode=True, default_flow_style=False).strip()


SUBSCRIPTS = str.maketrans("0123456789-+tTjmxy", "₀₁₂₃₄₅₆₇₈₉₋₊ₜₜⱼₘₓᵧ")


def unicode_math(text: str) -> str:
    """The docstrings' plain-text maths in clean Unicode, outside code spans: Sigma_{t-1} → Σₜ₋₁, m^2 → m²,
    sqrt → √, 20 x 20 m → 20 × 20 m."""
    parts = re.split(r"(`[^`]*`)", text)
    for i in range(0, len(parts), 2):  # the even parts lie outside code spans
        part = re.sub(
            r"\bSigma_(?:\{([^}]*)\}|([0-9tTjmxy]+))",
            lambda m: (
                "Σ" + (m.group(1) or m.group(2)).translate(SUBSCRIPTS)
                if set(m.group(1) or m.group(2)) <= set("0123456789-+tTjmxy")
                else m.group(0).replace("Sigma", "Σ")
            ),
            parts[i],
        )
        part = re.sub(r"\bSigma\b", "Σ", part)
        part = re.sub(r"\^2\b", "²", part)
        part = re.sub(r"\bsqrt\b", "√", part)
        part = re.sub(r"(\d) x (\d)", r"\1 × \2", part)
        parts[i] = part.replace(" +- ", " ± ").replace("<=", "≤").replace(">=", "≥")
    return "".join(parts)


def render_env_page(env_id: str, generated: str, recipes: Mapping[str, str] | None = None) -> str:
    import gymnasium as gym

    from ekfslam_gym.envs import EKFSLAMEnv
    from ekfslam_gym.envs.episode import step_limit

    doc = EKFSLAMEnv.__doc__ or ""
    described = re.search(rf"``{re.escape(env_id)}``: (.*?)(?=\n\s*- ``|\n\s*\n|\Z)", doc, re.S)
    env = gym.make(env_id)
    base = env.unwrapped
    config = base.config
    steps = step_limit(config)  # the env's own episode length in env steps, v0 and v1 alike
    seconds = steps * config.dt * (config.action.hold if config.action.kind != "velocity" else 1)
    name, version = family(env_id)
    image = DOCS / "images" / f"{env_id}.png"
    if not image.is_file():
        raise SystemExit(f"{image.relative_to(ROOT)} is missing: run python docs/stills.py")
    lines = [
        f"# {env_id}",
        "",
        generated,
        "",
        "| | |",
        "|---|---|",
        f"| Action space | `{env.action_space}` |",
        f"| Observation space | `{env.observation_space}` |",
        "| Reward range | (−∞, ∞): the drop in log det Σ in nats a step, plus the weighted terms of "
        "[the reward](../spaces-and-reward.md#reward) |",
        f"| Episode length | {steps} env steps ({seconds:g} s simulated); "
        + (
            "earlier if every landmark is known well enough or on a collision, as configured |"
            if config.terminate_on_complete
            else "a fixed horizon: a complete map does not end it (`info['time_to_complete']` says when) |"
        ),
        f'| Import | `import ekfslam_gym; gymnasium.make("{env_id}")` |',
        "",
        "## Description",
        "",
        unicode_math(" ".join((described.group(1) if described else "").split())),
        f"A differential-drive robot among {config.world.n_landmarks} point landmarks in the "
        f"`{config.world.layout}` layout reads ranges and bearings; the EKF-SLAM inside the env fuses them "
        "with odometry, and the agent observes that filter's belief, never the true map "
        "([the environments](../environment.md)).",
        "",
        f"Set apart from the defaults of `EnvConfig()`: {_differences(config)}.",
        "",
        f"![{env_id}: the belief mid-episode, the frontier planner driving](../images/{env_id}.png)",
        "",
        'The frame `render_mode="rgb_array"` returns, its legend below the map: the true world in black and '
        "grey, the filter's estimates with their 3σ ellipses (blue: landmarks, red: the robot), the region "
        "the sensor sees from the true pose shaded, cut by the walls. "
        '`render_options={"legend": False}` drops the legend, `{"landmark_ellipse_scale": 5}` magnifies '
        "the landmark ellipses.",
        "",
        "```python",
        "import gymnasium as gym",
        "",
        "import ekfslam_gym  # noqa: F401  (registers the ids)",
        "",
        f'env = gym.make("{env_id}", render_mode="rgb_array")',
        "obs, info = env.reset(seed=0)",
        "obs, reward, terminated, truncated, info = env.step(env.action_space.sample())",
        "frame = env.render()  # (640, 640, 3) uint8",
        "env.close()",
        "```",
        "",
    ]
    table = headline_table(env_id)
    if table:
        lines += [
            "## Results",
            "",
            "The held-out suite (seeds 10000-10049, 50 episodes), interquartile mean [95 % bootstrap "
            "confidence interval]; every agent and every metric: [Results](../results.md) and "
            f"[the full table as CSV](../results/{env_id}.csv).",
            "",
            *table,
            "",
        ]
    lines += [
        "## Configuration",
        "",
        f'Everything `gym.make("{env_id}")` builds, every field written out (`env.unwrapped.config.to_dict()`); '
        "any of it can be overridden as a section, e.g. "
        f'`gym.make("{env_id}", sensor={{"max_range": 4.0}})` ([Configuration](../configuration.md)).',
        "",
        "```yaml",
        _yaml(config.to_dict()),
        "```",
        "",
    ]
    lines += _shipped_policy(env_id, recipes or {})
    lines += ["## Version history", "", "| id | package | what changed |", "|---|---|---|"]
    for entry in version_history(env_id):
        vid = f"{name}-v{entry['version']}"
        shown = f"**{vid}**" if vid == env_id else vid
        lines.append(f"| {shown} | {entry['package']} | {' '.join(str(entry['change']).split())} |")
    lines += ["", "What a new version means: [Versions](../versioning.md).", ""]
    env.close()
    del version
    return "\n".join(lines)


def _flow(data: Any) -> str:
    import yaml

    return yaml.safe_dump(dict(data), default_flow_style=True, sort_keys=False).strip()


def _differences(config: Any) -> str:
    """The fields where ``config`` differs from ``EnvConfig()``, as ``name: value`` code spans."""
    import dataclasses

    from ekfslam_gym.envs import EnvConfig

    def leaves(obj: Any, prefix: str = "") -> dict[str, Any]:
        out: dict[str, Any] = {}
        for f in dataclasses.fields(obj):
            value = getattr(obj, f.name)
            if dataclasses.is_dataclass(value):
                out.update(leaves(value, f"{prefix}{f.name}."))
            else:
                out[f"{prefix}{f.name}"] = value
        return out

    mine, defaults = leaves(config), leaves(EnvConfig())
    changed = [
        f"`{k}: {_flow(v) if isinstance(v, dict) else v}`" for k, v in mine.items() if v != defaults.get(k)
    ]
    return ", ".join(changed) if changed else "nothing (this id is the defaults)"


def _shipped_policy(env_id: str, recipes: Mapping[str, str]) -> list[str]:
    """The section on the id's shipped policy: its own (v0), or the generalist's (every v1 layout id, and the
    mix it was trained on); none for an id without one."""
    import yaml

    from ekfslam_gym.pretrained import shipped_policy_file

    try:
        model = shipped_policy_file(env_id)
    except ValueError:
        return []
    record = yaml.safe_load(model.with_name(f"{model.stem}_config.yaml").read_text())
    entry, trained_on = record["entry"], record["env_id"]
    recipe = recipes.get(trained_on)
    rerun = (
        f"in a checkout of the repository, `python train.py --config {recipe} --env-id {trained_on} --seed "
        f"{record['seed']}` trains it again"
        if recipe
        else "its training record is shipped beside it"
    )
    if trained_on == env_id:
        about = "Its env settings on top of this id's:"
        picture = f"![the shipped policy on held-out seed 10001](../{model.stem}.gif)"
    else:
        about = (
            f"It is the [generalist](../generalist.md), shipped for every v1 layout id: trained on "
            f"`{trained_on}` (the training families only) and run here as it is, with its env settings on top of "
            "this id's (the reward weights do not change what it does):"
        )
        picture = f"![the generalist on {GIF_ENV}, a held-out family, seed 10001](../{model.stem}.gif)"
    return [
        "## The shipped policy",
        "",
        f"`{entry.get('algo', 'ppo')}` with `{entry['policy']}`, trained for {entry['n_timesteps']:,} "
        f'decisions; `ekfslam_gym.load_pretrained("{env_id}")` loads it (the `train` extra) and '
        "`agent.make_env()` builds the env it was trained on. " + about,
        "",
        "```yaml",
        _yaml(entry.get("env_kwargs", {})),
        "```",
        "",
        picture,
        "",
        f"How it was trained ({rerun}) and found: [Training](../training.md) and [the research "
        f"log](../{'research-log' if trained_on == env_id else 'research-log-generalist'}.md).",
        "",
    ]

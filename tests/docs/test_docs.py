"""The README, the docs and the configs cannot drift from the code.

- (every Python block of the docs runs, from outside the checkout: ``tests/docs/test_site.py``);
- every repository path, dotted ``ekfslam_gym`` name, command-line flag and config key they name exists
  (the research log, a record of experiments, is held to paths and flags only: options it tried may be gone);
- the generated pages and ``configs/env/default.yaml`` match the code (``docs/generate.py --check``), and every
  config field has its unit and note;
- ``configs/`` holds the shipped recipes and at most five examples, each readable alone, and each shipped recipe
  reproduces its model's training record field for field; the experiment configs still load.
"""

from __future__ import annotations

import contextlib
import importlib
import io
import math
import re
import subprocess
import sys
from functools import cache
from pathlib import Path

import numpy as np
import pytest
import yaml

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
MARKDOWN = [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]
HISTORY = {path for path in MARKDOWN if path.name.startswith("research-log")}
# Files other branches create; the integrator removes a name from here once its file has landed.
PENDING_PATHS = {"CHANGELOG.md"}
FILE_SUFFIXES = {"json", "npz", "yaml", "md", "py", "png", "csv", "zip", "dat", "txt", "g2o", "pkl"}
ENV_SECTIONS = ("world", "robot", "sensor", "odometry", "filter", "reward", "observation", "action")
PATH_PREFIXES = ("ekfslam_gym/", "agents/", "configs/", "models/", "docs/", "tests/", "bench/", ".ci/")
TOP_FILES = {"train.py", "demo.py", "Makefile", "pyproject.toml", "setup.py", "CITATION.cff", "LICENSE",
             "README.md", "mkdocs.yml", "CHANGELOG.md"}  # fmt: skip


def _generate():
    spec = importlib.util.spec_from_file_location("docs_generate", DOCS / "generate.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _rel(path: Path) -> str:
    return str(path.relative_to(ROOT))


def _code(text: str) -> list[str]:
    """Every code span and code block of a Markdown text."""
    blocks = re.findall(r"^```[^\n]*\n(.*?)^```", text, re.S | re.M)
    prose = re.sub(r"^```[^\n]*\n.*?^```", "", text, flags=re.S | re.M)
    return blocks + re.findall(r"`([^`\n]+)`", prose)


# The python blocks run from an empty folder outside the checkout: tests/docs/test_site.py.


# ------------------------------------------------------------------------------------ names exist
def _path_tokens(page: Path) -> set[str]:
    tokens = set()
    for code in _code(page.read_text()):
        for token in re.split(r"[\s,;()\[\]'\"=]+", code):
            token = token.rstrip(".:")
            if token.startswith(PATH_PREFIXES) or token in TOP_FILES:
                if not re.search(r"[<>*{]|(?<![A-Za-z])ID(?![A-Za-z])|\.\.\.", token):
                    tokens.add(token)
    links = re.findall(r"\]\(([^)#\s]+)|<img src=\"([^\"]+)\"", page.read_text())
    links = [link for pair in links for link in pair if link]
    if page.parent == ROOT:  # the README's links are repository paths
        tokens |= {link for link in links if not link.startswith("http")}
    return tokens


@pytest.mark.parametrize("page", MARKDOWN, ids=_rel)
def test_named_repository_paths_exist(page: Path) -> None:
    missing = sorted(t for t in _path_tokens(page) if t not in PENDING_PATHS and not (ROOT / t).exists())
    assert not missing, f"{_rel(page)} names paths that do not exist: {missing}"


def _importable(dotted: str) -> bool:
    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        try:
            for name in parts[i:]:
                obj = getattr(obj, name)
        except AttributeError:
            return False
        return True
    return False


@pytest.mark.parametrize("page", MARKDOWN, ids=_rel)
def test_named_python_objects_exist(page: Path) -> None:
    names = {m for code in _code(page.read_text()) for m in re.findall(r"\bekfslam_gym(?:\.\w+)+", code)}
    names = {n.removesuffix(".py") for n in names if not n.endswith((".yaml", ".md", ".zip"))}
    missing = sorted(n for n in names if not _importable(n))
    assert not missing, f"{_rel(page)} names objects that do not import: {missing}"


COMMANDS = {
    "train.py": "train",
    "demo.py": "demo",
    **{f"ekfslam_gym.{name}": f"ekfslam_gym.cli.{name}" for name in
       ("evaluate", "replay", "graph", "smoothing", "consistency", "sweep", "tradeoff", "compare")},
}  # fmt: skip


@cache
def _flags(command: str) -> frozenset[str]:
    """The flags a command's --help lists (scripts under docs/ and bench/: the flags their source defines)."""
    if command.startswith(("docs/", "bench/")):
        return frozenset(re.findall(r"[\"'](--[a-z][a-z0-9-]*)", (ROOT / command).read_text()))
    sys.path.insert(0, str(ROOT))
    try:
        module = importlib.import_module(COMMANDS[command])
        out = io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.suppress(SystemExit):
            module.main(["--help"])
    finally:
        sys.path.remove(str(ROOT))
    return frozenset(re.findall(r"(?<![\w-])--[a-z][a-z0-9-]*", out.getvalue())) | {"--help"}


def _command_lines(page: Path) -> list[tuple[str, list[str]]]:
    """(command, its flags) for every command line in a page's code."""
    found = []
    for code in _code(page.read_text()):
        for line in code.replace("\\\n", " ").split("\n"):
            pattern = (r"(?:python\s+(?:-m\s+)?|ekfslam-)(train\.py|demo\.py|(?:docs|bench)/\w+\.py|"
                       r"ekfslam_gym\.\w+|evaluate|replay|graph|smoothing|consistency|sweep|tradeoff|compare)\b")  # fmt: skip
            matches = list(re.finditer(pattern, line))
            for i, match in enumerate(matches):
                end = matches[i + 1].start() if i + 1 < len(matches) else len(line)
                command = match.group(1)
                if not command.endswith(".py") and not command.startswith("ekfslam_gym."):
                    command = f"ekfslam_gym.{command}"
                if command not in COMMANDS and not (ROOT / command).is_file():
                    continue
                segment = re.sub(r"'[^']*'|\"[^\"]*\"", "", line[match.end() : end])
                flags = [
                    f.split("=")[0] for f in re.findall(r"(?<![\w-])--[a-z][a-z0-9-]*(?:=\S*)?", segment)
                ]
                found.append((command, flags))
    return found


@pytest.mark.parametrize("page", MARKDOWN, ids=_rel)
def test_named_command_line_flags_exist(page: Path) -> None:
    lines = _command_lines(page)
    unknown = sorted({(c, f) for c, flags in lines for f in flags if f not in _flags(c)})
    assert not unknown, f"{_rel(page)} names flags its commands do not take: {unknown}"


def _env_fields() -> dict[str, set[str]]:
    import dataclasses

    from ekfslam_gym.envs import EnvConfig

    config = EnvConfig()
    fields = {"": {f.name for f in dataclasses.fields(config)}}
    for section in ENV_SECTIONS:
        fields[section] = {f.name for f in dataclasses.fields(getattr(config, section))}
    return fields


def _pretrain_keys() -> set[str]:
    sys.path.insert(0, str(ROOT))
    try:
        from ekfslam_gym.training.settings import load_entry

        return set(load_entry(ROOT / "configs" / "ppo_primitives_bc.yaml", "EKFSLAM-v0")["pretrain"])
    finally:
        sys.path.remove(str(ROOT))


def _config_keys(page: Path) -> set[tuple[str, str]]:
    """(section, key) for every `section.key` and every key of an inline `section: {...}` / `section={...}`."""
    keys = set()
    sections = "|".join((*ENV_SECTIONS, "pretrain"))
    for code in _code(page.read_text()):
        dotted = re.findall(rf"(?<![\w./\"'-])({sections})\.([a-z_][a-z0-9_]*)\b", code)
        keys |= {(s, k) for s, k in dotted if k not in FILE_SUFFIXES}
        for section, body in re.findall(rf"\b({sections})\"?\s*[:=]\s*\{{([^{{}}]*)\}}", code):
            keys |= {(section, key) for key in re.findall(r"[\"']?([a-z_][a-z0-9_]*)[\"']?\s*:", body)}
    return keys


def _runtime_attribute(section: str, key: str) -> bool:
    """`filter.copy()` or `world.pose` name the env's filter or world objects, not config keys."""
    from ekfslam_gym.filter import EKFSLAM
    from ekfslam_gym.sim.world import World

    return hasattr({"filter": EKFSLAM, "world": World}.get(section, object), key)


@pytest.mark.parametrize("page", [p for p in MARKDOWN if p not in HISTORY], ids=_rel)
def test_named_config_keys_and_reward_terms_exist(page: Path) -> None:
    fields, pretrain = _env_fields(), _pretrain_keys()
    unknown = sorted(
        f"{s}.{k}"
        for s, k in _config_keys(page)
        if k not in (pretrain if s == "pretrain" else fields[s]) and not _runtime_attribute(s, k)
    )
    assert not unknown, f"{_rel(page)} names config keys that do not exist: {unknown}"


def test_the_consistency_checks_catch_what_they_are_for(tmp_path) -> None:
    """Each check fails on a page naming something that does not exist (the checks above are not vacuous)."""
    page = tmp_path / "page.md"
    page.write_text(
        "Set `reward.map_quality` or `reward: {coverage: 1.0, return_home: 2}`; read `configs/nothing.yaml` and "
        "`ekfslam_gym.envs.NoSuchThing`.\n\n```bash\nekfslam-evaluate --agent greedy --no-such-flag\n"
        "python train.py --config configs/ppo.yaml --seed 0\n```\n"
    )
    keys = {f"{s}.{k}" for s, k in _config_keys(page)}
    assert {"reward.map_quality", "reward.return_home", "reward.coverage"} <= keys
    fields = _env_fields()
    assert "map_quality" not in fields["reward"] and "coverage" in fields["reward"]
    assert "configs/nothing.yaml" in _path_tokens(page) and not (ROOT / "configs/nothing.yaml").exists()
    assert not _importable("ekfslam_gym.envs.NoSuchThing") and _importable("ekfslam_gym.envs.EnvConfig")
    lines = _command_lines(page)
    assert ("ekfslam_gym.evaluate", ["--agent", "--no-such-flag"]) in lines
    assert "--no-such-flag" not in _flags("ekfslam_gym.evaluate") and "--agent" in _flags(
        "ekfslam_gym.evaluate"
    )
    assert ("train.py", ["--config", "--seed"]) in lines and "--seed" in _flags("train.py")


# ------------------------------------------------------------------------------------ generated files
def test_generated_pages_and_default_yaml_match_the_code() -> None:
    assert _generate().main(["--check"]) == 0


def test_configs_env_default_yaml_is_every_field_at_its_default() -> None:
    from ekfslam_gym.envs import EnvConfig

    data = yaml.safe_load((ROOT / "configs" / "env" / "default.yaml").read_text())
    assert EnvConfig.from_overrides(**data) == EnvConfig()
    assert data == EnvConfig().to_dict()  # every field written out, none left to a default


def test_every_config_field_has_a_unit_and_a_note(monkeypatch) -> None:
    generate = _generate()
    generate._check_notes()
    notes = dict(generate.FIELD_NOTES)
    notes.pop("sensor.max_range")
    monkeypatch.setattr(generate, "FIELD_NOTES", notes)
    with pytest.raises(SystemExit, match="sensor.max_range"):
        generate._check_notes()


def test_rst_tables_become_markdown_tables() -> None:
    generate = _generate()
    rst = "\n".join([
        "==== ==== ========",
        "part size contents",
        "==== ==== ========",
        "pose 4    the pose,",
        "          continued",
        "cov_ 3    ``ln`` of",
        "ers       variances",
        "==== ==== ========",
    ])  # fmt: skip
    assert generate.rst_to_markdown(rst).strip().split("\n") == [
        "| part | size | contents |",
        "|---|---|---|",
        "| pose | 4 | the pose, continued |",
        "| cov_ers | 3 | `ln` of variances |",
    ]


# ------------------------------------------------------------------------------------ configs
def _load(config: Path, env_id: str) -> dict:
    sys.path.insert(0, str(ROOT))
    try:
        from ekfslam_gym.training.settings import resolve_entry  # the trainer's own loader

        return resolve_entry(config, env_id)
    finally:
        sys.path.remove(str(ROOT))


@pytest.mark.parametrize("env_id", sorted(_generate().SHIPPED_RECIPES))
def test_each_shipped_recipe_reproduces_its_models_record(env_id: str) -> None:
    """The recipe, read by the trainer, is the record's entry field for field; only where the run read its
    demonstrations (pretrain.path: a run of the same settings collected them) and pretrain keys added after the
    record was written (at their defaults) may differ."""
    recipe = ROOT / _generate().SHIPPED_RECIPES[env_id]
    record = yaml.safe_load((ROOT / "models" / f"ppo_{env_id}_config.yaml").read_text())
    assert record["env_id"] == env_id
    entry, recorded = _load(recipe, env_id), dict(record["entry"])
    if recorded.get("pretrain"):
        recorded["pretrain"] = dict(recorded["pretrain"], path=None)
        for key, value in entry["pretrain"].items():
            if key not in recorded["pretrain"]:
                assert value in (None, False), f"pretrain.{key} was added after the record with a non-default"
                recorded["pretrain"][key] = value
    recorded.setdefault("algo", "ppo")  # a record written before the key existed trained PPO ...
    recorded.setdefault("pretrain", None)  # ... and cloned nothing
    assert entry == recorded


TOP_CONFIGS = sorted((ROOT / "configs").glob("*.yaml"))
EXAMPLES = {"ppo.yaml", "ppo_waypoint.yaml", "ppo_primitives_bc.yaml", "ppo_lstm.yaml", "ppo_belief_cnn.yaml"}


def test_configs_top_level_holds_the_shipped_recipes_and_the_examples() -> None:
    recipes = {Path(p).name for p in _generate().SHIPPED_RECIPES.values()}
    assert {p.name for p in TOP_CONFIGS} == recipes | EXAMPLES
    assert len(EXAMPLES - recipes) <= 5


@pytest.mark.parametrize("config", TOP_CONFIGS, ids=lambda p: p.name)
def test_top_level_configs_are_readable_alone(config: Path) -> None:
    """A header says what the file is for and what it reached; every setting the trainer uses is written in it
    (nothing left to the loader's defaults), and it names no other config as its base."""
    text = config.read_text()
    header = text.split("\n\n")[0] if text.startswith("#") else ""
    assert re.match(r"# (SHIPPED RECIPE|EXAMPLE)", header) and "Reached:" in header and "Run:" in header
    raw = yaml.safe_load(text)
    settings = raw.pop("train_settings", None) or {}
    for env_id, entry in raw.items():
        written = dict(entry, **(settings.get(env_id) or {}))
        resolved = _load(config, env_id)
        assert set(resolved) <= set(written), (
            f"{config.name} {env_id}: {set(resolved) - set(written)} unwritten"
        )
        if resolved["pretrain"]:
            assert set(resolved["pretrain"]) <= set(written["pretrain"])


EXPERIMENTS = sorted((ROOT / "configs" / "experiments").glob("*.yaml"))


@pytest.mark.parametrize("config", EXPERIMENTS, ids=lambda p: p.name)
def test_experiment_configs_load_and_are_indexed(config: Path) -> None:
    for env_id in (k for k in yaml.safe_load(config.read_text()) if k != "train_settings"):
        assert _load(config, env_id)["n_timesteps"] > 0
    assert f"`{config.name}`" in (config.parent / "README.md").read_text()


def test_scripts_in_docs_have_help() -> None:
    """docs/generate.py, docs/stills.py, docs/comparison.py and docs/generalist.py are runnable scripts with
    --help."""
    for script in ("generate.py", "stills.py", "comparison.py", "generalist.py"):
        out = io.StringIO()
        with contextlib.redirect_stdout(out), pytest.raises(SystemExit) as exit_:
            _help(DOCS / script)
        assert exit_.value.code == 0 and "usage" in out.getvalue()


def _help(script: Path) -> None:
    spec = importlib.util.spec_from_file_location(script.stem, script)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    module.main(["--help"])


def test_comparison_figure_draws_from_per_episode_json(tmp_path, monkeypatch) -> None:
    """docs/comparison.py: evaluate's --episodes-json into docs/data/ CSV, then the box plots (an outlier far
    off is counted, not drawn to scale)."""
    import json

    import numpy as np

    pytest.importorskip("matplotlib")
    spec = importlib.util.spec_from_file_location("docs_comparison", DOCS / "comparison.py")
    comparison = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(comparison)
    monkeypatch.setattr(comparison, "DATA", tmp_path / "data")
    rng = np.random.default_rng(0)
    keys = [key for key, _, _ in comparison.PANELS]
    episodes = {
        name: [dict({k: float(rng.uniform(0.01, 1.0)) for k in keys}, seed=10000 + i) for i in range(8)]
        for name in ("greedy", "frontier", "ppo[best_model]")
    }
    episodes["greedy"][0]["map_log_det"] = 1e6
    (tmp_path / "episodes.json").write_text(json.dumps(episodes))
    assert comparison.main(["--from-json", str(tmp_path / "episodes.json"), "EKFSLAM-v0", "--out",
                            str(tmp_path / "comparison.png")]) == 0  # fmt: skip
    assert (tmp_path / "comparison.png").stat().st_size > 0
    assert set(comparison.read("EKFSLAM-v0")) == {"greedy", "frontier", "ppo"}


def test_docs_page_is_generated_from_the_current_docstring():
    from pathlib import Path

    script = Path(__file__).resolve().parents[2] / "docs" / "generate.py"
    result = subprocess.run([sys.executable, str(script), "--check"], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr


def test_the_generalist_curve_times_a_checkpoint_from_its_run(tmp_path) -> None:
    """docs/generalist.py: a run starts at its monitors' earliest t_start, and a process's CPU time at a moment is
    interpolated between the sampler's lines (NaN for a process it never saw)."""
    spec = importlib.util.spec_from_file_location("docs_generalist", DOCS / "generalist.py")
    generalist = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generalist)
    for name, start in (("0", 100.5), ("1", 99.0)):
        path = tmp_path / "run" / "monitor" / "from_0" / f"{name}.monitor.csv"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(f'#{{"t_start": {start}, "env_id": "EKFSLAM-Mix-v1"}}\nr,l,t\n')
    assert generalist.run_starts(tmp_path / "run") == {0: 99.0}  # the earliest t_start of its monitors
    resumed = tmp_path / "run" / "monitor" / "from_300" / "0.monitor.csv"
    resumed.parent.mkdir()
    resumed.write_text('#{"t_start": 5000.0, "env_id": "EKFSLAM-Mix-v1"}\nr,l,t\n')
    starts = generalist.run_starts(tmp_path / "run")
    assert starts == {0: 99.0, 300: 5000.0}
    assert [generalist.part_of(starts, steps) for steps in (0, 20, 300, 320)] == [0, 0, 0, 300]
    log = tmp_path / "cpu.log"
    log.write_text("100.0 7:10.0 8:1.0\n110.0 7:14.0 8:2.0\n")
    assert generalist.cpu_at(log, 7, 105.0) == pytest.approx(12.0)
    assert generalist.cpu_at(log, 8, 120.0) == pytest.approx(2.0)
    assert math.isnan(generalist.cpu_at(log, 9, 105.0))


def test_the_generalist_spread_draws_the_same_seeds_for_both_agents() -> None:
    """docs/generalist.py spread: an agent a constant above the other on every seed is above it in every draw
    (the draws pair the seeds), an agent equal to it is at or below it in every draw, and a draw's IQM is the
    mean of its middle half."""
    spec = importlib.util.spec_from_file_location("docs_generalist", DOCS / "generalist.py")
    generalist = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generalist)
    whole = generalist.draws_of({"a": np.arange(8.0)}, 8, 1, np.random.default_rng(0))["a"]
    assert whole == pytest.approx(
        [np.mean([2.0, 3.0, 4.0, 5.0])]
    )  # a draw of every seed: its middle half's mean
    frontier = np.random.default_rng(1).lognormal(-3.0, 0.8, 50)
    drawn = generalist.draws_of(
        {"generalist": frontier + 0.01, "frontier": frontier}, 10, 500, np.random.default_rng(2)
    )
    assert drawn["frontier"].shape == (500,)
    assert np.allclose(drawn["generalist"] - drawn["frontier"], 0.01)
    assert np.ptp(drawn["frontier"]) > 0.01  # the draws differ from each other

    def rows(gap: float) -> list[dict]:
        return [
            {
                "agent": agent,
                "family": family,
                "seed": seed,
                "landmark_rmse": value + (gap if agent == "generalist" else 0),
            }
            for family in ("arena", "maze")
            for agent in ("generalist", "frontier")
            for seed, value in enumerate(frontier)
        ]

    assert generalist.spread(rows(0.0), draws=200).splitlines()[-1].endswith("| 100.0% |")
    assert generalist.spread(rows(0.01), draws=200).splitlines()[-1].endswith("| 0.0% |")


def test_the_generalist_interfaces_expected_rmse_is_the_marginal_covariances_mean_trace() -> None:
    """docs/generalist.py interfaces: the RMSE the filter expects is sqrt of the mean over the seen landmarks of
    the trace of each landmark's 2 x 2 block, which under consistency is what the squared errors average to;
    and the table gives each agent's IQM and median per family."""
    import gymnasium as gym

    spec = importlib.util.spec_from_file_location("docs_generalist", DOCS / "generalist.py")
    generalist = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generalist)
    env = gym.make("EKFSLAM-v1")
    env.reset(seed=20000)
    for _ in range(40):
        env.step(np.array([0.6, 0.3], dtype=np.float32))
    ekf = env.unwrapped.filter
    cov, seen = np.asarray(ekf.cov), np.flatnonzero(np.asarray(ekf.observed))
    assert 0 < seen.size < len(np.asarray(ekf.observed))  # some seen, some not: the unseen must be left out
    traces = [np.trace(cov[3 + 2 * j : 5 + 2 * j, 3 + 2 * j : 5 + 2 * j]) for j in seen]
    assert generalist.expected_rmse(env) == pytest.approx(math.sqrt(np.mean(traces)), rel=1e-12)
    env.close()

    rows = [
        {"agent": agent, "family": "arena", "seed": seed, "map_log_det": -600 - seed - shift,
         "landmark_rmse": 0.01 * (seed + 1) + shift / 100, "expected_rmse": 0.05, "path_length": 100 + seed}
        for agent, shift in (("a", 0), ("b", 10))
        for seed in range(8)
    ]  # fmt: skip
    table = generalist.interfaces(rows).splitlines()
    assert table[0] == "| agent | arena |"
    assert table[2] == "| a | -603.5 / 0.045 / 0.050 / 104 |"  # IQM of 2..5 and the median of 100..107
    assert table[3] == "| b | -613.5 / 0.145 / 0.050 / 104 |"

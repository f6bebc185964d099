"""The shipped policies and recipes travel with the package and are found from any folder; a saved model brings
its env (``ekfslam_gym.packaged``, ``ekfslam_gym.pretrained``, ``evaluate``'s env resolution)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import ekfslam_gym
from ekfslam_gym import packaged
from ekfslam_gym.pretrained import resolve_env_id

ROOT = Path(__file__).resolve().parent.parent
IDS = sorted(
    [*(i for i in gym.registry if i.startswith("EKFSLAM") and i.endswith("-v0")), "EKFSLAM-Mix-v1"]
)  # the ids with a policy file of their own: the v0 specialists and the generalist


def test_every_top_level_recipe_is_packaged_and_nothing_else():
    assert packaged.config_names() == sorted(p.stem for p in (ROOT / "configs").glob("*.yaml"))
    assert packaged.shipped_env_ids() == IDS


@pytest.mark.parametrize("given", ["ppo", "ppo.yaml", "configs/ppo.yaml"])
def test_a_recipe_resolves_by_name_from_any_folder(given, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    resolved = packaged.resolve_config(given)
    assert resolved.read_text() == (ROOT / "configs" / "ppo.yaml").read_text()


def test_a_config_path_wins_over_a_packaged_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "ppo.yaml").write_text("EKFSLAM-v0: {}\n")
    assert packaged.resolve_config("ppo.yaml") == Path("ppo.yaml")


def test_an_unknown_config_names_the_packaged_recipes(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(
        FileNotFoundError,
        match=r"config nope does not exist \(neither a file nor a packaged recipe; packaged recipes: ppo, ",
    ):
        packaged.resolve_config("nope")
    with pytest.raises(FileNotFoundError):  # a folder other than configs/ is a path, never a recipe name
        packaged.resolve_config("elsewhere/ppo.yaml")


def test_an_env_without_a_shipped_policy_is_named():
    with pytest.raises(ValueError, match="no shipped policy for 'EKFSLAM-v9'; shipped: EKFSLAM-Large-v0"):
        packaged.shipped_model("EKFSLAM-v9")


class _Trained:
    def __init__(self, env_id):
        self.trained_env_id = env_id

    def __repr__(self):
        return f"model({self.trained_env_id})"


def test_a_model_brings_its_env_and_a_different_one_needs_force():
    large, loop = _Trained("EKFSLAM-Large-v0"), _Trained("EKFSLAM-Loop-v0")
    assert resolve_env_id([large, object()], None) == "EKFSLAM-Large-v0"
    assert resolve_env_id([object()], None) == "EKFSLAM-v0"
    assert resolve_env_id([large], "ekfslam_gym:EKFSLAM-Large-v0") == "ekfslam_gym:EKFSLAM-Large-v0"
    with pytest.raises(ValueError, match=r"model\(EKFSLAM-Large-v0\) was trained on EKFSLAM-Large-v0, not "
                       r"EKFSLAM-v0: leave out --env-id .* or add --force"):  # fmt: skip
        resolve_env_id([large], "EKFSLAM-v0")
    with pytest.raises(ValueError, match=r"trained on different envs \(EKFSLAM-Large-v0, EKFSLAM-Loop-v0\)"):
        resolve_env_id([large, loop], None)
    with pytest.warns(UserWarning, match="was trained on EKFSLAM-Large-v0, evaluated on EKFSLAM-v0"):
        assert resolve_env_id([large], "EKFSLAM-v0", force=True) == "EKFSLAM-v0"


def test_evaluate_without_env_id_runs_the_model_on_its_own_env(capsys):
    from ekfslam_gym.cli.evaluate import main

    model = str(ROOT / "models" / "ppo_EKFSLAM-Loop-v0.zip")
    argv = ["--agent", "ppo", "--model", model, "--seeds", "0", "--max-episode-steps", "2", "--no-progress"]
    assert main(argv) == 0
    assert capsys.readouterr().out.startswith("EKFSLAM-Loop-v0, 1 seeds")
    with pytest.raises(SystemExit):
        main([*argv, "--env-id", "EKFSLAM-v0"])
    assert "was trained on EKFSLAM-Loop-v0, not EKFSLAM-v0" in capsys.readouterr().err


def test_make_env_for_model_gives_what_plain_sb3_predicts_on():
    """The v0 policy was trained with other env settings than the id's defaults (primitives, a Dict
    observation): the env built from its record, statistics included, is what its own agent sees."""
    path = packaged.shipped_model("EKFSLAM-v0")
    venv = ekfslam_gym.make_env_for_model(path, seed=3)
    model = ekfslam_gym.load_model(path)
    action, _ = model.predict(venv.reset(), deterministic=True)
    _, reward, _, _ = venv.step(action)

    agent = ekfslam_gym.load_pretrained("EKFSLAM-v0")
    env = agent.make_env()
    observation, _ = env.reset(seed=3)
    agent.reset(env, 3)
    assert venv.observation_space == env.observation_space
    _, own_reward, *_ = env.step(agent.act(observation))
    np.testing.assert_allclose(reward[0], own_reward, rtol=1e-6)  # the VecEnv's rewards are float32


def test_loading_needs_no_top_level_agents_module(tmp_path):
    """Outside the checkout no ``agents`` module exists: the v0 model's pickled policy_kwargs name
    ``agents.extractors.BeliefCNN``, so loading must rebuild them from the record."""
    code = (
        "import sys, ekfslam_gym\n"
        "agent = ekfslam_gym.load_pretrained('EKFSLAM-v0')\n"
        "print(type(agent.model.policy.features_extractor).__module__)\n"
        "print(any(m == 'agents' or m.startswith('agents.') for m in sys.modules))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, check=True
    )
    assert out.stdout.split() == ["ekfslam_gym.agents.extractors", "False"]


def test_a_record_naming_the_top_level_agents_package_is_refused(tmp_path):
    """``agents.extractors`` is not a module name (the folder installs as ``ekfslam_gym.agents``): the load says
    which name it could not import rather than building a second copy of the class."""
    stem = tmp_path / "model"
    for suffix in (".zip", "_vecnormalize.pkl"):
        (tmp_path / f"model{suffix}").write_bytes((ROOT / "models" / f"ppo_EKFSLAM-v0{suffix}").read_bytes())
    record = (ROOT / "models" / "ppo_EKFSLAM-v0_config.yaml").read_text()
    Path(f"{stem}_config.yaml").write_text(
        record.replace("ekfslam_gym.agents.extractors", "agents.extractors")
    )
    with pytest.raises(ValueError, match="cannot import 'agents.extractors.BeliefCNN'"):
        ekfslam_gym.load_model(stem)


def test_version_is_written_once():
    from importlib.metadata import version

    assert version("ekfslam-gym") == ekfslam_gym.__version__
    assert "version =" not in (ROOT / "pyproject.toml").read_text().split("[project]")[1].split("[")[0]


@pytest.mark.parametrize("command", ["ekfslam_gym.cli.train", "ekfslam_gym.cli.sweep"])
def test_the_training_commands_name_the_packaged_recipes(command, tmp_path, monkeypatch, capsys):
    import importlib

    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit):
        importlib.import_module(command).main(
            ["--config", "nope", "--seeds", "0"][: 2 if "train" in command else 4]
        )
    assert (
        "config nope does not exist (neither a file nor a packaged recipe; packaged recipes: ppo,"
        in capsys.readouterr().err
    )


def test_the_sweep_resolves_its_default_config_from_any_folder(tmp_path, monkeypatch):
    from ekfslam_gym.cli import sweep

    monkeypatch.chdir(tmp_path)
    args = sweep._build_parser().parse_args(["--seeds", "0"])
    assert packaged.resolve_config(args.config) == packaged.resolve_config("ppo").resolve()


# ---------------------------------------------------------------------------------------------- the generalist
def test_every_v1_layout_id_gets_the_generalist_and_nothing_else_does():
    from ekfslam_gym.envs.presets import FAMILY_IDS, GENERALIST_IDS, MIX_ID
    from ekfslam_gym.pretrained import shipped_policy_file

    generalist = packaged.shipped_model(MIX_ID)
    assert set(GENERALIST_IDS) == {*FAMILY_IDS, "EKFSLAM-Large-v1"}
    for env_id in GENERALIST_IDS:
        assert shipped_policy_file(env_id) == generalist
        assert shipped_policy_file(f"ekfslam_gym:{env_id}") == generalist
        with pytest.raises(ValueError, match=f"no shipped policy for '{env_id}'"):
            packaged.shipped_model(env_id)  # the files: the generalist has one, not one per id
    assert shipped_policy_file("EKFSLAM-Large-v0").name == "ppo_EKFSLAM-Large-v0.zip"  # v0 keeps its own
    with pytest.raises(ValueError, match="no shipped policy for 'EKFSLAM-Large-v2'"):
        shipped_policy_file("EKFSLAM-Large-v2")


def test_a_policy_trained_on_the_mix_runs_on_every_v1_layout_id_and_only_there():
    from ekfslam_gym.envs.presets import GENERALIST_IDS

    mixed = _Trained("EKFSLAM-Mix-v1")
    for env_id in (*GENERALIST_IDS, "EKFSLAM-Mix-v1"):
        assert resolve_env_id([mixed], env_id) == env_id
    assert resolve_env_id([mixed], None) == "EKFSLAM-Mix-v1"
    with pytest.raises(ValueError, match="was trained on EKFSLAM-Mix-v1, not EKFSLAM-v0"):
        resolve_env_id([mixed], "EKFSLAM-v0")  # the v0 task is another task
    with pytest.raises(ValueError, match="was trained on EKFSLAM-Maze-v1, not EKFSLAM-Rooms-v1"):
        resolve_env_id([_Trained("EKFSLAM-Maze-v1")], "EKFSLAM-Rooms-v1")  # only the mix generalises by name


def test_the_generalist_drives_every_v1_layout_id_at_every_tier():
    """The shipped generalist: its record names the mix and the recipe; loaded by any v1 layout id, it runs on
    that id's worlds (the spaces are the mix's) with its LSTM state. Nothing about how well."""
    from ekfslam_gym.artefacts import record_beside
    from ekfslam_gym.benchmark.generalisation import zero_shot_settings
    from ekfslam_gym.envs.presets import GENERALIST_IDS

    pytest.importorskip("sb3_contrib")
    model = packaged.shipped_model("EKFSLAM-Mix-v1")
    record = record_beside(model)
    assert record.env_id == "EKFSLAM-Mix-v1" and record.algo == "ppo_lstm"
    assert record.entry["pretrain"]["planner"] == "frontier"  # the recipe: cloned, then fine-tuned
    assert "configs/ppo_lstm_generalist_bc.yaml" in model.with_name(f"{model.stem}_config.yaml").read_text()
    for env_id in GENERALIST_IDS:
        agent = ekfslam_gym.load_pretrained(env_id)
        assert agent.trained_env_id == "EKFSLAM-Mix-v1" and agent.recurrent
        tiers = ("easy", "hard") if env_id != "EKFSLAM-Large-v1" else (None,)
        for tier in tiers:
            settings = {**zero_shot_settings(agent.trained_env_kwargs), **({"tier": tier} if tier else {})}
            env = gym.make(env_id, max_episode_steps=3, **settings)
            assert env.observation_space == agent.make_env().observation_space
            observation, _ = env.reset(seed=20000)
            agent.reset(env, 20000)
            done = False
            while not done:
                action = agent.act(observation)
                assert env.action_space.contains(action)
                observation, _, terminated, truncated, _ = env.step(action)
                done = terminated or truncated
            env.close()


def test_evaluate_gives_the_generalist_for_a_v1_layout_id_without_model(capsys):
    from ekfslam_gym.cli.evaluate import main

    argv = ["--agent", "ppo", "--env-id", "EKFSLAM-Maze-v1", "--seeds", "20000", "--max-episode-steps", "2",
            "--no-progress"]  # fmt: skip
    assert main(argv) == 0
    assert capsys.readouterr().out.startswith("EKFSLAM-Maze-v1, 1 seeds")

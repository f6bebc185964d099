"""The files of a training run: one set of names for the writer and the readers, and one parser of the record
(the trainer's resume, the PPO agent and ``load_pretrained`` all read it through ``RunRecord``)."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from ekfslam_gym.agents.ppo import saved_algo

from ekfslam_gym import artefacts
from ekfslam_gym.artefacts import (
    ModelFiles,
    RunRecord,
    latest_checkpoint,
    model_paths,
    read_run,
    record_beside,
)
from ekfslam_gym.pretrained import model_env
from ekfslam_gym.training.artefacts import write_record

ROOT = Path(__file__).resolve().parents[1]


def test_a_models_files_are_named_from_its_stem_with_or_without_zip(tmp_path):
    for given in (tmp_path / "run" / "best_model", tmp_path / "run" / "best_model.zip"):
        files = ModelFiles.of(given)
        assert files.stem == tmp_path / "run" / "best_model"
        assert files.zip.name == "best_model.zip" and files.vecnormalize.name == "best_model_vecnormalize.pkl"
        assert (
            files.record.name == "best_model_config.yaml"
            and files.versions.name == "best_model_versions.json"
        )
        assert files.rng.name == "best_model_rng.pkl"
        assert model_paths(given) == (files.zip, files.vecnormalize)
    checkpoint = artefacts.checkpoint_files(tmp_path, 512)
    assert checkpoint.zip == tmp_path / "checkpoints" / "ppo_512_steps.zip"


def test_the_latest_checkpoint_is_the_most_steps_not_the_last_name(tmp_path):
    assert latest_checkpoint(tmp_path) is None
    for steps in (512, 1024, 96):
        (tmp_path / f"ppo_{steps}_steps.zip").write_bytes(b"")
    (tmp_path / "ppo_x_steps.zip").write_bytes(b"")  # not a checkpoint's name
    (tmp_path / "ppo_4096_steps_vecnormalize.pkl").write_bytes(b"")  # statistics, not a model
    assert latest_checkpoint(tmp_path) == (tmp_path / "ppo_1024_steps.zip", 1024)


def test_the_record_the_trainer_writes_reads_back_the_same(tmp_path):
    entry = {"algo": "ppo_lstm", "env_kwargs": {"action": {"kind": "primitives", "hold": 10}}, "n_envs": 2,
             "policy_kwargs": {"net_arch": [64, 64]}}  # fmt: skip
    write_record(tmp_path, "EKFSLAM-Large-v0", 3, entry, ["--seed", "3"])
    written = yaml.safe_load((tmp_path / artefacts.RECORD_FILE).read_text())
    assert list(written) == ["env_id", "seed", "entry", "argv"] and written["argv"] == ["--seed", "3"]
    record = read_run(tmp_path)
    assert record == ("EKFSLAM-Large-v0", 3, entry)
    env_id, seed, read_entry = record  # what a resume unpacks
    assert (env_id, seed, read_entry) == ("EKFSLAM-Large-v0", 3, entry)
    assert record.algo == "ppo_lstm" and record.env_kwargs == entry["env_kwargs"]
    assert record.policy_kwargs == {"net_arch": [64, 64]}
    assert (tmp_path / artefacts.VERSIONS_FILE).is_file()
    assert RunRecord(None, None, {}).algo == "ppo" and RunRecord(None, None, {}).env_kwargs is None


def test_a_bad_record_is_named_with_what_is_wrong(tmp_path):
    with pytest.raises(FileNotFoundError, match="not a training run folder"):
        read_run(tmp_path)
    path = tmp_path / artefacts.RECORD_FILE
    for text, message in (("[1, 2]", "a mapping"), ("env_id: [x]", "env_id must be"),
                          ("env_id: E\nseed: one", "seed must be an integer"), ("entry: 3", "entry must be"),
                          ("env_id: E\nentry: {}", "no seed"), ("{bad", "not a readable")):  # fmt: skip
        path.write_text(text)
        with pytest.raises(ValueError, match=message) as raised:
            read_run(tmp_path)
        assert str(path) in str(raised.value)


def test_a_models_own_record_comes_before_its_folders(tmp_path):
    model = tmp_path / "model.zip"
    assert record_beside(model) is None  # a model saved by hand
    (tmp_path / artefacts.RECORD_FILE).write_text("env_id: EKFSLAM-v0\nseed: 0\nentry: {algo: ppo}\n")
    assert record_beside(model).env_id == "EKFSLAM-v0"
    ModelFiles.of(model).record.write_text(
        "env_id: EKFSLAM-Loop-v0\nseed: 1\nentry: {env_kwargs: {max_episode_steps: 9}}\n"
    )
    assert record_beside(model) == ("EKFSLAM-Loop-v0", 1, {"env_kwargs": {"max_episode_steps": 9}})
    assert model_env(model) == ("EKFSLAM-Loop-v0", {"max_episode_steps": 9})  # load_pretrained's reader
    ModelFiles.of(model).record.write_text("- not a record\n")
    assert record_beside(model) is None  # unreadable: as if there were none
    with pytest.raises(ValueError, match="no training record naming the env"):
        model_env(model)


def test_the_algo_comes_from_the_record_when_there_is_one(tmp_path):
    model = tmp_path / "model.zip"
    assert saved_algo(model, RunRecord("EKFSLAM-v0", 0, {"algo": "ppo_lstm"})) == "ppo_lstm"
    assert saved_algo(model, None) == "ppo"  # no record and no readable zip: the default


@pytest.mark.parametrize("env_id", ["EKFSLAM-v0", "EKFSLAM-Loop-v0", "EKFSLAM-Large-v0"])
def test_every_shipped_model_has_a_complete_record(env_id):
    record = record_beside(ROOT / "models" / f"ppo_{env_id}.zip")
    assert record is not None and record.env_id == env_id and isinstance(record.seed, int)
    assert record.algo in ("ppo", "ppo_lstm") and isinstance(record.env_kwargs, dict)

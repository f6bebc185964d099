"""The paired comparison of two groups of models on the same seeds (``ekfslam_gym.evaluation.paired``) and its
command line (``ekfslam-compare``)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ekfslam_gym.cli.compare import main
from ekfslam_gym.evaluation.metrics import bootstrap_ci, iqm
from ekfslam_gym.evaluation.paired import paired_difference


def _model(values, seeds=None, metric="landmark_rmse"):
    seeds = range(len(values)) if seeds is None else seeds
    return [{"seed": int(s), metric: float(v)} for s, v in zip(seeds, values)]


def test_a_constant_shift_is_recovered_exactly_and_identical_groups_differ_by_nothing():
    rng = np.random.default_rng(0)
    models = [rng.normal(0.12, 0.05, 40) for _ in range(3)]
    a = [_model(m) for m in models]
    shifted = [_model(m + 0.02) for m in models]
    same = paired_difference(a, a, "landmark_rmse")
    assert same.difference == 0.0 and same.ci == (0.0, 0.0) and same.seeds == 40
    moved = paired_difference(shifted, a, "landmark_rmse")
    assert moved.a == pytest.approx(iqm(np.concatenate(models)) + 0.02, abs=1e-12)
    assert moved.difference == pytest.approx(0.02, abs=1e-12)
    assert moved.ci == pytest.approx((0.02, 0.02), abs=1e-12)  # every resample moves both sides together


def test_pairing_by_seed_removes_the_seeds_shared_part_from_the_interval():
    """When the seed explains most of a metric, the seed-resampled interval of the difference is far narrower
    than the two groups' own intervals added, and it still covers the true shift (seeded, with a margin)."""
    rng = np.random.default_rng(1)
    hardness = rng.normal(0.0, 1.0, 60)
    a = [_model(hardness + rng.normal(0.0, 0.1, 60)) for _ in range(2)]
    b = [_model(hardness + 0.3 + rng.normal(0.0, 0.1, 60)) for _ in range(2)]
    result = paired_difference(a, b, "landmark_rmse")
    lo, hi = result.ci
    assert lo < -0.3 < hi
    own = [bootstrap_ci(np.array([e["landmark_rmse"] for m in g for e in m])) for g in (a, b)]
    unpaired_half_widths = sum((h - l) / 2 for l, h in own)
    assert (hi - lo) / 2 < 0.25 * unpaired_half_widths


def test_episode_order_does_not_matter_and_nans_are_left_out():
    values = np.linspace(0.05, 0.3, 30)
    a = [_model(values)]
    b = [_model(np.full(30, 0.1), seeds=range(29, -1, -1))]  # the same seeds, listed backwards
    with_nan = [_model(np.r_[values[:-1], np.nan])]
    assert paired_difference(a, b, "landmark_rmse").difference == pytest.approx(iqm(values) - 0.1)
    assert paired_difference(with_nan, b, "landmark_rmse").a == pytest.approx(iqm(values[:-1]))


@pytest.mark.parametrize(
    "a, b, message",
    [
        ([_model([1.0, 2.0])], [_model([1.0, 2.0], seeds=[0, 5])], "different seeds"),
        ([_model([1.0, 2.0]), _model([1.0], seeds=[0])], [_model([1.0, 2.0])], "other seeds than model 0"),
        ([_model([1.0, 2.0], seeds=[3, 3])], [_model([1.0, 2.0])], "more than once"),
        ([], [_model([1.0])], "no models"),
    ],
)
def test_groups_on_different_seeds_are_refused(a, b, message):
    with pytest.raises(ValueError, match=message):
        paired_difference(a, b, "landmark_rmse")


def test_the_command_reads_evaluate_files_and_selects_an_entry(tmp_path, capsys):
    base = np.linspace(-300.0, -100.0, 20)

    def episodes(shift):
        return [{"seed": 20000 + i, "map_log_det": v + shift, "landmark_rmse": 0.1, "ate": 0.1}
                for i, v in enumerate(base)]  # fmt: skip

    new, old = tmp_path / "new.json", tmp_path / "old.json"
    new.write_text(json.dumps({"ppo[model]": episodes(-25.0), "ppo[bc_model]": episodes(0.0)}))
    old.write_text(json.dumps({"ppo[model]": episodes(0.0)}))
    assert main(["--a", str(new), "--b", str(old), "--key", "ppo[model]", "--metric", "map_log_det"]) == 0
    out = capsys.readouterr().out
    assert "1 models" in out and "on 20 seeds" in out and "= -25 [-25, -25]" in out
    with pytest.raises(SystemExit):
        main(["--a", str(new), "--b", str(old), "--key", "ppo[best_model]"])
    assert "has no entry 'ppo[best_model]'" in capsys.readouterr().err

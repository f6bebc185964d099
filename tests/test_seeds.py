"""The seed policy (``ekfslam_gym.seeds``): the ranges, the names the command lines take, the checks, and that
evaluation defaults to the evaluation seeds, never the held-out suite."""

from __future__ import annotations

import inspect

import pytest

from ekfslam_gym import seeds
from ekfslam_gym.cli import evaluate
from ekfslam_gym.evaluation.rollout import evaluate_agent


def test_the_ranges_do_not_overlap():
    held_out, evaluation = set(seeds.HELD_OUT_SEEDS), set(seeds.EVAL_SEEDS)
    assert seeds.HELD_OUT_SEEDS == tuple(range(10000, 10050)) and seeds.HELD_OUT == "10000-10049"
    assert seeds.EVAL_SEEDS[0] == seeds.EVAL_SEED_START == 20000 and len(evaluation) == len(held_out)
    assert seeds.SELECTION_SEEDS == tuple(range(20000, 20010))
    assert not held_out & evaluation
    assert seeds.DEMONSTRATION_SEED_START > max(evaluation)


@pytest.mark.parametrize(
    ("text", "expected"),
    [("3-6", [3, 4, 5, 6]), ("1,4,9", [1, 4, 9]), ("0-2,10", [0, 1, 2, 10]), ("heldout", list(range(10000, 10050))),
     ("held-out", list(range(10000, 10050))), ("eval", list(range(20000, 20050)))],
)  # fmt: skip
def test_parse_seeds_reads_ranges_and_suite_names(text, expected):
    assert seeds.parse_seeds(text) == expected


@pytest.mark.parametrize(
    ("text", "message"), [("5-2", "empty seed range"), ("a-b", "suite"), ("", "no seeds")]
)
def test_parse_seeds_says_what_is_wrong(text, message):
    with pytest.raises(ValueError, match=message):
        seeds.parse_seeds(text)


def test_span_round_trips_through_parse_seeds():
    for values in ([20000, 20001, 20002], [1, 5, 9], [7]):
        assert seeds.parse_seeds(seeds.span(values)) == values
    assert seeds.suite_name(seeds.parse_seeds("heldout")) == "heldout" and seeds.suite_name([1, 2]) is None


def test_held_out_seeds_are_refused_by_name():
    assert seeds.held_out_overlap([9999, 10000, 10049, 10050]) == [10000, 10049]
    assert seeds.check_not_held_out([20000, 20001], "evaluation seeds") == [20000, 20001]
    with pytest.raises(
        ValueError, match="evaluation seeds \\[10049\\] are in the held-out suite 10000-10049"
    ):
        seeds.check_not_held_out([9999, 10049], "evaluation seeds")


def test_demonstration_seeds_avoid_the_held_out_and_evaluation_seeds():
    assert seeds.check_demonstration_seeds(range(30000, 30003)) == [30000, 30001, 30002]
    for bad in ([10000], [10049], [20005], [-1]):
        with pytest.raises(ValueError, match="held-out suite \\(10000-10049\\)"):
            seeds.check_demonstration_seeds(bad)
    assert seeds.check_demonstration_seeds([20005], eval_seeds=[20100]) == [20005]


def test_evaluation_defaults_to_the_evaluation_seeds():
    assert inspect.signature(evaluate_agent).parameters["seeds"].default == seeds.EVAL_SEEDS
    parser = evaluate._build_parser()
    assert parser.parse_args([]).seeds == list(seeds.EVAL_SEEDS)
    assert parser.parse_args(["--seeds", "heldout"]).seeds == list(seeds.HELD_OUT_SEEDS)
    assert "--seeds heldout" in parser.description and "20000-20049" in parser.format_help()

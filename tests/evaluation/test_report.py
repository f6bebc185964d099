"""The report functions take what aggregate.summary returns, one or many, and say what to pass otherwise."""

from __future__ import annotations

import pytest

from ekfslam_gym.evaluation.aggregate import aggregate, summary
from ekfslam_gym.evaluation.report import markdown_table, text_summary

EPISODES = [{"ate": 0.1, "map_log_det": 3.0}, {"ate": 0.2, "map_log_det": 4.0}]
KEYS = ["ate", "map_log_det"]


def test_one_summary_is_a_table_of_one_row_with_its_own_metrics():
    one = summary("greedy", EPISODES, keys=KEYS)
    table = markdown_table(one)
    assert table == markdown_table({"greedy": one})
    header, _, row = table.splitlines()[:3]
    assert header == "| agent | episodes | ate ↓ | map_log_det ↓ |"  # the summary's metrics, not METRIC_KEYS
    assert row.startswith("| greedy | 2 | 0.15 [")


def test_aggregate_alone_is_refused_with_the_call_that_works():
    with pytest.raises(TypeError, match=r"aggregate\(\)'s metrics.*pass summary\(name, episodes\)"):
        markdown_table(aggregate(EPISODES, keys=KEYS))
    with pytest.raises(TypeError, match=r"pass summary\(name, episodes\)"):
        text_summary(aggregate(EPISODES, keys=KEYS))


def test_a_missing_metric_names_the_row_and_its_metrics():
    with pytest.raises(KeyError, match=r"'greedy' has no metric 'return'; it has \['ate', 'map_log_det'\]"):
        markdown_table({"greedy": summary("greedy", EPISODES, keys=KEYS)}, ["return"])


def test_text_summary_takes_one_summary_alone_or_keyed():
    one = summary("greedy", EPISODES, keys=KEYS)
    assert text_summary(one) == text_summary({"greedy": one})
    assert text_summary(one).startswith("greedy: 2 episodes")
    with pytest.raises(TypeError, match="expected one summary"):
        text_summary({"a": one, "b": summary("b", EPISODES, keys=KEYS)})

"""evaluate's plain-text block keeps its columns straight whatever the metric names."""

from __future__ import annotations

from ekfslam_gym.evaluation.report import text_summary

SUMMARY = {
    "agent": "circle",
    "episodes": 2,
    "metrics": {
        "return": {"iqm": 617.0, "ci": [575.0, 659.0], "mean": 617.0},
        "belief_truth_spearman": {"iqm": 0.0908, "ci": [0.0555, 0.13], "mean": 0.0908},
        "map_nees": {"iqm": 1.02, "ci": [0.81, 1.23], "mean": 1.02},
    },
}


def test_every_column_starts_where_its_header_does() -> None:
    header, *rows = text_summary(SUMMARY).splitlines()[1:]
    ci_column = header.index("95% CI")
    iqm_end = header.index("IQM") + len("IQM")
    for row in rows:
        assert row[ci_column] == "[", row
        assert row[iqm_end - 1] != " " and row[iqm_end] == " ", row

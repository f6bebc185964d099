"""Argument types the command lines share."""

from __future__ import annotations

import argparse
from collections.abc import Mapping
from typing import Any

from .. import seeds


def parse_seeds(text: str) -> list[int]:
    """``--seeds``: a suite's name (``heldout``, ``eval``), ``A-B`` (inclusive), ``A,B,C``, or a mix such as
    ``0-4,10`` (``ekfslam_gym.seeds.parse_seeds``)."""
    try:
        return seeds.parse_seeds(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def merge_env_kwargs(
    trained: Mapping[str, Any] | None, overrides: Mapping[str, Any] | None
) -> dict[str, Any]:
    """A trained policy's recorded env settings with command-line ``--env-kwargs`` on top, section by section:
    ``{"filter": {"variant": "fej"}}`` changes the variant and keeps the rest of the record's ``filter``."""
    merged: dict[str, Any] = {
        key: dict(v) if isinstance(v, Mapping) else v for key, v in (trained or {}).items()
    }
    for key, value in (overrides or {}).items():
        if isinstance(value, Mapping) and isinstance(merged.get(key), Mapping):
            merged[key] = {**merged[key], **value}
        else:
            merged[key] = value
    return merged

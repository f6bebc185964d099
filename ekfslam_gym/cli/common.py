"""Argument types the command lines share."""

from __future__ import annotations

import argparse

from .. import seeds
from ..evaluation.rollout import merge_env_kwargs  # noqa: F401  (the command lines read it here)


def parse_seeds(text: str) -> list[int]:
    """``--seeds``: a suite's name (``heldout``, ``eval``), ``A-B`` (inclusive), ``A,B,C``, or a mix such as
    ``0-4,10`` (``ekfslam_gym.seeds.parse_seeds``)."""
    try:
        return seeds.parse_seeds(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None

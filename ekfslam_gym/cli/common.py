"""Argument types the command lines share."""

from __future__ import annotations

import argparse
from collections.abc import Mapping
from typing import Any


def parse_seeds(text: str) -> list[int]:
    """``A-B`` (inclusive), ``A,B,C``, or a mix such as ``0-4,10``."""
    seeds: list[int] = []
    try:
        for part in filter(None, (p.strip() for p in text.split(","))):
            lo, _, hi = part.partition("-")
            first, last = int(lo), int(hi or lo)
            if last < first:
                raise argparse.ArgumentTypeError(f"empty seed range {part!r}")
            seeds.extend(range(first, last + 1))
    except ValueError:
        raise argparse.ArgumentTypeError(f"seeds must look like A-B or A,B,C, got {text!r}") from None
    if not seeds:
        raise argparse.ArgumentTypeError(f"no seeds in {text!r}")
    return seeds


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

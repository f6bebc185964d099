"""Argument types the command lines share."""

from __future__ import annotations

import argparse


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

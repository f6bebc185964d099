"""The one line parser of the text formats the readers share (the course files, MRCLAM, GTSAM 2-D, g2o).

Each of those formats is a sequence of records, one a line, of whitespace-separated tokens. ``read_records``
yields the non-blank lines of a file with their numbers, every file is read as UTF-8 (ASCII is a subset; a byte
that is not UTF-8 becomes U+FFFD and then fails to parse, on its line), and every error a ``Record`` raises
names the file's full path and the line: ``/data/MRCLAM_Dataset1/Robot1_Odometry.dat:12: v 'x' is not a
number``. What each token means is the format's reader's business; only the checks every format makes
(a count of fields, a finite number, an integer in range) are here.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

__all__ = ["ENCODING", "Record", "read_records"]

ENCODING = "utf-8"


@dataclass(frozen=True, slots=True)
class Record:
    """One non-blank line: its file, its 1-based number and its tokens (comments removed)."""

    path: Path
    line: int
    tokens: list[str]

    @property
    def where(self) -> str:
        """``path:line``, the prefix of every error about this record."""
        return f"{self.path}:{self.line}"

    def error(self, message: str) -> ValueError:
        """A ``ValueError`` whose message starts with ``path:line``."""
        return ValueError(f"{self.where}: {message}")

    def expect(self, values: int, what: str, *, tagged: bool = False) -> None:
        """Raise unless the record holds ``values`` values, after its first token when ``tagged`` (``what``
        names the line, and its fields where that helps)."""
        got = len(self.tokens) - tagged
        if got != values:
            raise self.error(f"{what} line needs {values} values, got {got}: {' '.join(self.tokens)!r}")

    def number(self, index: int, what: str) -> float:
        """Token ``index`` as a finite float."""
        token = self.tokens[index]
        try:
            value = float(token)
        except ValueError:
            raise self.error(f"{what} {token!r} is not a number") from None
        if not math.isfinite(value):
            raise self.error(f"{what} {token!r} is not finite")
        return value

    def numbers(self, start: int, what: str) -> list[float]:
        """Tokens ``start:`` as finite floats."""
        return [self.number(i, what) for i in range(start, len(self.tokens))]

    def integer(self, index: int, what: str, minimum: int | None = None) -> int:
        """Token ``index`` as an int, at least ``minimum`` when given."""
        token = self.tokens[index]
        try:
            value = int(token)
        except ValueError:
            raise self.error(f"{what} {token!r} is not an integer") from None
        if minimum is not None and value < minimum:
            raise self.error(f"{what} {value} must be >= {minimum}")
        return value


def read_records(path: str | os.PathLike[str], comment: str | None = "#") -> Iterator[Record]:
    """The records of the text file at ``path``: every line with a token once the text from ``comment`` on is
    dropped (None: no comments in the format). ``FileNotFoundError`` names the path."""
    path = Path(path)
    with path.open("r", encoding=ENCODING, errors="replace") as handle:
        for number, line in enumerate(handle, start=1):
            if comment is not None:
                line = line.split(comment, 1)[0]
            tokens = line.split()
            if tokens:
                yield Record(path, number, tokens)

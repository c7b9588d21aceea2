"""CSV files the kit writes, safe to open in a spreadsheet.

Control characters (terminal escapes) are dropped from every cell. A cell that begins with ``=``, ``+``, ``-``, ``@``, a tab or a carriage return is a formula to a
spreadsheet, and text in the kit's CSVs comes from students (a folder named ``=2+5``, a note that
quotes their file name). Every CSV writer of the kit goes through ``writer``, which prefixes such a
cell with a single quote, as OWASP's rule on CSV injection says. A number stays a number: ``-0.5``
(a score, a penalty) is written as it is, since no spreadsheet reads a plain number as a formula.
"""

from __future__ import annotations

import csv
import re
from collections.abc import Iterable
from typing import IO

FORMULA_START = ("=", "+", "-", "@", "\t", "\r")
NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
"""A plain decimal number, as ``f"{x:g}"`` and ``str`` write them (no ``inf`` or ``nan``)."""


CONTROL = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f-\x9f]")
"""Control characters other than tab and line ends: ``cat grades.csv`` would pass an escape sequence from a
student's error message to the terminal (adversarial review of issue 31)."""


def cell(value: object) -> object:
    """``value`` as it is safe to write in a CSV cell: control characters other than tab and line ends are
    dropped, and text that a spreadsheet would read as a formula gets a leading ``'``; numbers, and text that
    is a plain number, are kept."""
    if isinstance(value, str):
        value = CONTROL.sub("", value)
        if value.startswith(FORMULA_START) and not NUMBER.fullmatch(value):
            return "'" + value
    return value


class Writer:
    """``csv.writer`` whose every cell goes through ``cell``."""

    def __init__(self, handle: IO[str]) -> None:
        self._writer = csv.writer(handle)

    def writerow(self, row: Iterable[object]) -> None:
        self._writer.writerow([cell(value) for value in row])


def writer(handle: IO[str]) -> Writer:
    """The CSV writer of the kit: ``csv.writer(handle)`` that neutralises formulas (``cell``)."""
    return Writer(handle)

"""Numbers in printed tables: columns that hold for any value.

A table printed with ``f"{x:>15.2f}"`` runs its columns together once a wrong filter makes x huge
(``636205078168245.5014069980227083452.00``). ``cell`` keeps at least one space before every
entry: a finite value too wide for its column in the usual notation is written in scientific
notation with as many digits as fit (a tiny one keeps the usual notation: 0.00), and inf, -inf and
nan are written as such.
"""

from __future__ import annotations

import math

SCIENTIFIC_DIGITS = 3
"""Digits after the point in scientific notation, fewer if the column is narrow."""


def number(value: float, spec: str = ".2f", room: int = 12) -> str:
    """``value`` formatted with ``spec`` (a format spec such as ".2f" or ".4g") in at most ``room``
    characters if it can be (a column narrower than 7 characters cannot hold every float)."""
    value = float(value)
    if math.isnan(value):
        return "nan"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    text = format(value, spec)
    if len(text) <= room and math.isfinite(float(text.rstrip("%"))):
        return text
    percent = spec.endswith("%") and math.isfinite(value * 100)  # else a fraction too large to scale
    scaled, suffix = (value * 100, "%") if percent else (value, "")
    for digits in range(SCIENTIFIC_DIGITS, -1, -1):
        text = f"{scaled:.{digits}e}{suffix}"
        if len(text) <= room:
            break
    return text


def cell(value: float, width: int, spec: str = ".2f") -> str:
    """``value`` right-aligned in a column of ``width`` characters, with at least one space before it."""
    return number(value, spec, width - 1).rjust(width)

"""Printed tables keep their columns for any value: course.tables, and the labs' tables that use it."""

from __future__ import annotations

import re
from decimal import Decimal

import numpy as np
import pytest

from course import tables
from course.air_traffic import FILTERS, QUANTITIES, print_robust_table, print_table
from course.train import load, print_model_comparison, print_rmse_table

VALUES = [0.0, 1.5, -2.25, 1e-300, -3e-12, 636205078168245.5, 6.0e307, -1.7976931348623157e308, np.inf, -np.inf, np.nan]


def _shown(text: str) -> Decimal:
    """The number a cell shows."""
    return Decimal(text[:-1]) / 100 if text.endswith("%") else Decimal(text)


def _last_digit(text: str) -> Decimal:
    """The value of one unit in the last digit that a cell shows."""
    mantissa, _, exponent = text.rstrip("%").partition("e")
    decimals = len(mantissa.partition(".")[2])
    unit = Decimal(10) ** (int(exponent or 0) - decimals)
    return unit / 100 if text.endswith("%") else unit


@pytest.mark.parametrize("spec", [".2f", ".3f", ".0f", ".1f", ".4g", ".0%"])
@pytest.mark.parametrize("width", [8, 11, 15])
def test_a_cell_has_its_width_and_a_space_before_it_for_any_value(spec, width):
    for value in VALUES:
        text = tables.cell(value, width, spec)
        assert len(text) == width and text[0] == " ", (value, spec, width, text)
        shown = text.strip()
        if np.isfinite(value):
            # the number it shows is the value, rounded to its last digit shown
            assert abs(Decimal(value) - _shown(shown)) <= _last_digit(shown) / 2 * Decimal("1.000001"), (value, shown)
        else:
            assert shown == {True: "nan", False: "inf" if value > 0 else "-inf"}[bool(np.isnan(value))]


def test_usual_values_keep_the_usual_notation():
    assert tables.cell(9.99, 15) == f"{9.99:>15.2f}"
    assert tables.cell(1e-300, 15) == f"{0.0:>15.2f}"  # tiny: rounded as the column's notation says
    assert tables.cell(19161.4, 11, ".0f") == f"{19161:>11d}"
    assert tables.cell(0.65, 8, ".0%") == "     65%"
    assert tables.cell(636205078168245.5, 15) == "      6.362e+14"


NUMBER = re.compile(r"-?\d+(\.\d+)?(e[+-]\d+)?%?|-?inf|nan")


def test_the_train_tables_keep_their_columns_for_huge_inf_and_nan(capsys):
    data = load()
    for wild in (6.36205078168245e14, 3.5e150, np.inf, np.nan):  # 3.5e150: a finite RMSE of 3.5e150
        estimate = np.full((len(data.minute), 2), wild)
        print_rmse_table(data, estimate)
        print_model_comparison(data, {"a wrong filter": estimate})
        lines = capsys.readouterr().out.splitlines()
        rows = [line[20:] for line in lines[1:3]] + [line[34:] for line in lines[4:]]
        assert len(rows) == 4
        for row in rows:
            numbers = row.split()
            assert len(numbers) == 2 and all(NUMBER.fullmatch(n) for n in numbers), row


def test_the_air_traffic_tables_keep_their_columns(capsys):
    row = {q: 6.36205078168245e14 for q in QUANTITIES} | {
        "lost_runs": 3, "diverged_runs": 4,
        "median": {"position": np.inf, "velocity": -1.7e308},
        "excluding_lost": {"position": np.nan, "velocity": 1e300},
        "excluding_diverged": {"velocity": 2e305},
        "time_averaged_rmse": {"position": 5e15},
    }
    table = {name: row for name in FILTERS}
    print_table(table, 10)
    print_robust_table(table)
    lines = capsys.readouterr().out.splitlines()
    n = len(FILTERS)
    metric, robust = lines[2:2 + n], lines[5 + n:5 + 2 * n]
    for line in metric:  # three "value (lecture's)" cells, the factor, lost, diverged
        tokens = line[10:].split()
        assert len(tokens) == 9 and all(NUMBER.fullmatch(t.strip("()")) or t == "(-)" for t in tokens), line
    for line in robust:  # six numbers, lost, diverged: none run together
        tokens = line[10:].split()
        assert len(tokens) == 8 and all(NUMBER.fullmatch(t) for t in tokens), line

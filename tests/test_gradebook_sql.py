"""The grades oracle (tests/gradebook_sql.py) can fail: grades.csv that disagrees with the gradebook
in any cell, the penalty, the total, the maximum or its rows is reported, on a gradebook written
here with SQL in nbgrader's table layout."""

import sqlite3

import pytest

from gradebook_sql import Sheet, csv_disagreements, sheets

SCHEMA = """
CREATE TABLE student (id TEXT PRIMARY KEY);
CREATE TABLE assignment (id TEXT PRIMARY KEY, name TEXT);
CREATE TABLE submitted_assignment (id TEXT PRIMARY KEY, assignment_id TEXT, student_id TEXT);
CREATE TABLE submitted_notebook (id TEXT PRIMARY KEY, assignment_id TEXT, late_submission_penalty REAL);
CREATE TABLE base_cell (id TEXT PRIMARY KEY, name TEXT);
CREATE TABLE grade_cells (id TEXT PRIMARY KEY, max_score REAL);
CREATE TABLE grade (id TEXT PRIMARY KEY, notebook_id TEXT, cell_id TEXT, auto_score REAL, manual_score REAL,
                    extra_credit REAL, needs_manual_grade BOOLEAN);
INSERT INTO student VALUES ('s1');
INSERT INTO assignment VALUES ('a1', 'lab');
INSERT INTO submitted_assignment VALUES ('sa1', 'a1', 's1');
INSERT INTO submitted_notebook VALUES ('sn1', 'sa1', 1.5);
INSERT INTO base_cell VALUES ('c1', 'test_a'), ('c2', 'test_b'), ('c3', 'written');
INSERT INTO grade_cells VALUES ('c1', 2.0), ('c2', 3.0), ('c3', 4.0);
INSERT INTO grade VALUES ('g1', 'sn1', 'c1', 2.0, NULL, NULL, 0), ('g2', 'sn1', 'c2', 0.0, 2.0, 0.5, 0),
                         ('g3', 'sn1', 'c3', NULL, NULL, NULL, 1);
"""

RIGHT = {"student": "s1", "lab": "lab", "test_a": "2", "test_b": "2.5", "written": "", "late_penalty": "1.5",
         "total": "3", "max_score": "9", "flagged": "", "notes": ""}


@pytest.fixture
def book(tmp_path):
    path = tmp_path / "gradebook.db"
    with sqlite3.connect(path) as connection:
        connection.executescript(SCHEMA)
    return sheets(f"sqlite:///{path}?timeout=120")


def test_the_gradebook_reads_as_nbgrader_scores_it(book):
    """The manual score wins over the automatic one, extra credit is added, a cell awaiting a hand
    grade has no score, and the penalty comes off the total."""
    assert book == {("s1", "lab"): Sheet({"test_a": (2.0, 2.0), "test_b": (2.5, 3.0), "written": (None, 4.0)}, 1.5)}
    assert csv_disagreements({("s1", "lab"): RIGHT}, book) == []


@pytest.mark.parametrize("column, value", [("test_a", "1"), ("test_b", "0"), ("written", "0"), ("late_penalty", "0"),
                                           ("total", "4.5"), ("max_score", "5")])
def test_any_wrong_column_is_reported(book, column, value):
    [error] = csv_disagreements({("s1", "lab"): RIGHT | {column: value}}, book)
    assert column in error


def test_a_missing_or_extra_row_is_reported(book):
    assert csv_disagreements({}, book) == ["('s1', 'lab'): in the gradebook, not in grades.csv"]
    extra = {("s1", "lab"): RIGHT, ("s2", "lab"): RIGHT | {"student": "s2"}}
    assert csv_disagreements(extra, book) == ["('s2', 'lab'): in grades.csv, not in the gradebook"]


def test_a_new_gradebook_gets_the_revision_that_nbgrader_asks_alembic_for(tmp_path):
    """autograder/pipeline/nbgrader_apps.py reads the revision in-process; nbgrader runs the `alembic heads`
    command for it. Both must write the same revision into a new gradebook."""
    import os
    import subprocess
    import sys

    from nbgrader.api import Gradebook
    from nbgrader.dbutil import _temp_alembic_ini

    from autograder.pipeline.nbgrader_apps import gradebook_schema_version

    with _temp_alembic_ini(f"sqlite:///{tmp_path / 'unused.db'}") as ini:
        heads = subprocess.run([os.path.join(os.path.dirname(sys.executable), "alembic"), "-c", ini, "heads"],
                               capture_output=True, text=True, check=True).stdout
    assert heads.split()[0] == gradebook_schema_version()
    with Gradebook(f"sqlite:///{tmp_path / 'gradebook.db'}"):
        pass
    with sqlite3.connect(tmp_path / "gradebook.db") as connection:
        assert connection.execute("SELECT version_num FROM alembic_version").fetchall() == [(heads.split()[0],)]

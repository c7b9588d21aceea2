"""The independent oracle for grades: the gradebook read with plain SQL, and grades.csv parsed back.

The grading pipeline reads the gradebook through nbgrader's ORM (``autograder.pipeline.grading.read_grades``)
and writes grades.csv from those rows. Comparing grades.csv with the rows it was written from, or
``read_grades`` with itself, cannot fail. Here the gradebook is read with SQL through the database's
own driver (``sqlite3`` or ``psycopg``), on nbgrader's tables, and grades.csv with the ``csv``
module; ``csv_disagreements`` compares the two, cell by cell. ``formgrader_gives`` and
``nbgrader_export`` do what an instructor does after grading written answers by hand.
"""

from __future__ import annotations

import csv
import sqlite3
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import psycopg
from nbgrader.api import Gradebook
from sqlalchemy.engine import make_url

from autograder.labs import ROOT

GRADES = """
SELECT student.id AS student, assignment.name AS lab, base_cell.name AS cell,
       grade.auto_score, grade.manual_score, grade.extra_credit, grade.needs_manual_grade,
       grade_cells.max_score, submitted_notebook.late_submission_penalty
FROM grade
JOIN submitted_notebook ON grade.notebook_id = submitted_notebook.id
JOIN submitted_assignment ON submitted_notebook.assignment_id = submitted_assignment.id
JOIN student ON submitted_assignment.student_id = student.id
JOIN assignment ON submitted_assignment.assignment_id = assignment.id
JOIN base_cell ON grade.cell_id = base_cell.id
JOIN grade_cells ON grade_cells.id = base_cell.id
"""


@dataclass
class Sheet:
    """One submission in the gradebook: cell -> (score, None while it awaits grading by hand; maximum)."""

    cells: dict[str, tuple[float | None, float]] = field(default_factory=dict)
    penalty: float = 0.0

    @property
    def total(self) -> float:
        return max(0.0, sum(score for score, _ in self.cells.values() if score is not None) - self.penalty)

    @property
    def max_score(self) -> float:
        return sum(maximum for _, maximum in self.cells.values())


def query(url: str, sql: str) -> list[dict]:
    """The rows of ``sql`` on the database at the SQLAlchemy ``url``, through sqlite3 or psycopg."""
    parsed = make_url(url)
    if parsed.get_backend_name() == "sqlite":
        connection = sqlite3.connect(f"file:{parsed.database}?mode=ro", uri=True)
    elif parsed.get_backend_name() == "postgresql":
        connection = psycopg.connect(host=parsed.host, port=parsed.port, user=parsed.username,
                                     password=parsed.password, dbname=parsed.database)
    else:
        raise ValueError(f"no driver for {url}")
    try:
        cursor = connection.cursor()
        cursor.execute(sql)
        names = [column[0] for column in cursor.description]
        return [dict(zip(names, values)) for values in cursor.fetchall()]
    finally:
        connection.close()


def sheets(url: str) -> dict[tuple[str, str], Sheet]:
    """(student, lab) -> Sheet, for every submission in the gradebook at ``url``."""
    out: dict[tuple[str, str], Sheet] = {}
    for g in query(url, GRADES):
        # nbgrader's Grade.score: the manual score if there is one, else the automatic one, plus extra credit
        points = g["manual_score"] if g["manual_score"] is not None else (g["auto_score"] or 0.0)
        score = None if g["needs_manual_grade"] else points + (g["extra_credit"] or 0.0)
        sheet = out.setdefault((g["student"], g["lab"]), Sheet())
        sheet.cells[g["cell"]] = (score, g["max_score"])
        sheet.penalty = g["late_submission_penalty"] or 0.0
    return out


def read_csv(path: Path) -> dict[tuple[str, str], dict[str, str]]:
    """grades.csv parsed back: (student, lab) -> its record."""
    with open(path, newline="") as handle:
        records = list(csv.DictReader(handle))
    table = {(r["student"], r["lab"]): r for r in records}
    assert len(table) == len(records), "grades.csv has two rows for one student and lab"
    return table


def number(text: str) -> float | None:
    return None if text == "" else float(text)


def csv_disagreements(table: dict[tuple[str, str], dict[str, str]], book: dict[tuple[str, str], Sheet]) -> list[str]:
    """Where grades.csv says something other than the gradebook: every cell, penalty, total, maximum."""
    errors = [f"{key}: in the gradebook, not in grades.csv" for key in book.keys() - table.keys()]
    errors += [f"{key}: in grades.csv, not in the gradebook" for key in table.keys() - book.keys()]
    every_cell = {cell for sheet in book.values() for cell in sheet.cells}
    for key in book.keys() & table.keys():
        record, sheet = table[key], book[key]
        errors += [f"grades.csv has no column {cell}" for cell in every_cell - set(record)]
        for cell in every_cell & set(record):  # a cell of another lab is empty
            score = sheet.cells.get(cell, (None, 0.0))[0]
            if number(record[cell]) != (None if score is None else float(f"{score:g}")):
                errors.append(f"{key} {cell}: grades.csv {record[cell]!r}, gradebook {score}")
        for column, value in (("late_penalty", sheet.penalty), ("total", sheet.total), ("max_score", sheet.max_score)):
            if float(record[column]) != float(f"{value:g}"):  # grades.csv writes numbers with :g
                errors.append(f"{key} {column}: grades.csv {record[column]!r}, gradebook {value}")
    return errors


def formgrader_gives(db_url: str, lab: str, student: str, scores: dict[str, float]) -> None:
    """What formgrader's grade API (nbgrader's GradeHandler.put) does when a grader saves a score
    by hand: the manual score, and no longer needing grading by hand."""
    with Gradebook(db_url) as gb:
        for name, score in scores.items():
            grade = gb.find_grade(name, lab, lab, student)
            grade.manual_score = score
            grade.needs_manual_grade = grade.manual_score is None and grade.auto_score is None
        gb.db.commit()


def nbgrader_export(workdir: Path, env: dict[str, str] | None = None) -> None:
    """`nbgrader export` as an instructor runs it from the course root, for the course ``workdir``:
    grades.csv rewritten from the gradebook with the hand scores (autograder/pipeline/export.py)."""
    subprocess.run([sys.executable, "-m", "nbgrader", "export", f"--CourseDirectory.root={workdir}"],
                   cwd=ROOT, env=env, check=True, capture_output=True)

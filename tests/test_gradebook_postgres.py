"""The gradebook in PostgreSQL, against a real server started on loopback for this module.

With GRADEBOOK_URL set, nbgrader_config.py points nbgrader at that database, so
`python -m autograder grade` and plain `nbgrader` both keep the gradebook there. A small class (a
blank and a solved submission of train-kf) graded into PostgreSQL gets the grades that SQLite
gives it, grades.csv agrees with the rows in PostgreSQL, and no SQLite gradebook is written.
The test needs Debian's `postgresql` package; without it, it fails (it never skips).
"""

import csv
import os
import shutil
import subprocess
import sys

import nbformat
import pytest
import sqlalchemy
from nbgrader.coursedir import CourseDirectory

import postgres_server
from autograder import grading, submissions
from autograder.labs import ROOT, get_lab

LABS = [get_lab("train-kf")]


@pytest.fixture(scope="module")
def postgres_url():
    """The SQLAlchemy URL of an empty database on a PostgreSQL server of this module's own."""
    reason = None
    try:
        with postgres_server.running_server() as url:
            yield url
    except postgres_server.ServerUnavailable as error:
        reason = str(error)
    if reason:  # outside the except block, so that the reason is reported once
        pytest.fail(reason, pytrace=False)


@pytest.fixture(scope="module")
def class_dir(tmp_path_factory):
    """A blank and a solved submission of each lab in LABS."""
    folder = tmp_path_factory.mktemp("class")
    for lab in LABS:
        blank, solved = nbformat.read(lab.release_notebook, as_version=4), submissions.solved(lab)
        for student, nb in ((submissions.BLANK, blank), (submissions.SOLVED, solved)):
            path = folder / student / lab.id / lab.notebook_name
            path.parent.mkdir(parents=True)
            nbformat.write(nb, path)
    return folder


@pytest.fixture(scope="module")
def graded_sqlite(class_dir, tmp_path_factory):
    workdir = tmp_path_factory.mktemp("sqlite-course")
    with pytest.MonkeyPatch.context() as patch:
        patch.delenv("GRADEBOOK_URL", raising=False)
        rows = grading.grade(class_dir, workdir)
    return {(row.student, row.lab): row for row in rows}


@pytest.fixture(scope="module")
def graded_postgres(postgres_url, class_dir, tmp_path_factory):
    """The class graded with GRADEBOOK_URL set: (student, lab) -> GradeRow, and the course folder."""
    workdir = tmp_path_factory.mktemp("postgres-course")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("GRADEBOOK_URL", postgres_url)
        rows = grading.grade(class_dir, workdir)
        assert grading.read_grades(workdir, LABS) == rows
    return {(row.student, row.lab): row for row in rows}, workdir


def query(url, sql):
    engine = sqlalchemy.create_engine(url)
    try:
        assert engine.dialect.name == "postgresql"
        with engine.connect() as connection:
            return connection.execute(sqlalchemy.text(sql)).mappings().all()
    finally:
        engine.dispose()


def test_the_configuration_follows_gradebook_url(monkeypatch, tmp_path):
    def db_url():
        return CourseDirectory(config=grading.course_config(tmp_path)).db_url

    monkeypatch.delenv("GRADEBOOK_URL", raising=False)
    assert db_url().startswith(f"sqlite:///{tmp_path / 'gradebook.db'}")
    url = "postgresql+psycopg://grader@db.example.org/course"
    monkeypatch.setenv("GRADEBOOK_URL", url)
    assert db_url() == url


def test_postgresql_gives_the_grades_that_sqlite_gives(graded_postgres, graded_sqlite):
    rows, _ = graded_postgres
    assert set(rows) == {(student, lab.id) for lab in LABS for student in (submissions.BLANK, submissions.SOLVED)}
    for key, row in rows.items():
        assert row == graded_sqlite[key], key
    for lab in LABS:
        blank, solved = rows[(submissions.BLANK, lab.id)], rows[(submissions.SOLVED, lab.id)]
        assert blank.auto_max > 0 and blank.auto_score == 0, blank.cells
        assert solved.auto_score == solved.auto_max, solved.lost


def test_the_grades_are_in_postgresql_and_grades_csv_agrees(graded_postgres, postgres_url):
    rows, workdir = graded_postgres
    assert not (workdir / "gradebook.db").exists(), "nbgrader wrote an SQLite gradebook despite GRADEBOOK_URL"
    grades = query(
        postgres_url,
        """
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
        """,
    )
    # (student, lab) -> cell -> (score, or None while it awaits grading by hand; maximum), and penalty
    in_db: dict[tuple[str, str], dict[str, tuple[float | None, float]]] = {}
    penalty: dict[tuple[str, str], float] = {}
    for g in grades:
        # nbgrader's Grade.score: the manual score if there is one, else the automatic one, plus extra credit
        points = g["manual_score"] if g["manual_score"] is not None else (g["auto_score"] or 0.0)
        score = None if g["needs_manual_grade"] else points + (g["extra_credit"] or 0.0)
        in_db.setdefault((g["student"], g["lab"]), {})[g["cell"]] = (score, g["max_score"])
        penalty[(g["student"], g["lab"])] = g["late_submission_penalty"] or 0.0
    assert set(in_db) == set(rows)
    every_cell = {cell for cells in in_db.values() for cell in cells}

    with open(workdir / "grades.csv") as handle:
        table = list(csv.DictReader(handle))
    assert len(table) == len(in_db)
    assert {(record["student"], record["lab"]) for record in table} == set(in_db)
    for record in table:
        key = (record["student"], record["lab"])
        cells = in_db[key]
        assert every_cell <= set(record), f"grades.csv lacks columns {every_cell - set(record)}"
        for cell in every_cell:  # a cell of another lab is empty
            expected = cells.get(cell, (None, 0.0))[0]
            assert record[cell] == ("" if expected is None else f"{expected:g}"), (key, cell)
        if "late_penalty" in record:
            assert float(record["late_penalty"]) == penalty[key]
        points = sum(score for score, _ in cells.values() if score is not None)
        assert float(record["total"]) == max(0.0, points - penalty[key]), key
        assert float(record["max_score"]) == sum(maximum for _, maximum in cells.values()), key


def test_plain_nbgrader_reads_the_postgresql_gradebook(graded_postgres, postgres_url, tmp_path):
    """`nbgrader db student list`, as an instructor types it, in a course folder that holds only
    nbgrader_config.py: it lists the students graded into PostgreSQL."""
    shutil.copy2(ROOT / "nbgrader_config.py", tmp_path / "nbgrader_config.py")
    env = {**os.environ, "GRADEBOOK_URL": postgres_url}  # PYTHONPATH (conftest.py) has the course root
    listing = subprocess.run(
        [sys.executable, "-m", "nbgrader", "db", "student", "list"],
        cwd=tmp_path, env=env, capture_output=True, text=True, check=True, timeout=60,
    )
    students = {line.split()[0] for line in listing.stdout.splitlines()[1:] if line.strip()}
    assert students == {student for student, _ in graded_postgres[0]}, listing.stdout
    assert not (tmp_path / "gradebook.db").exists()

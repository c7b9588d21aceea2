"""The grading round trip, through nbgrader, in a temporary course: the tests that
tests/test_round_trip.py and tests/test_round_trip_second_half.py both run, each on its half of the labs.

A blank submission scores 0, a solved one full marks, each catalogued mistake loses its own blank's
points and keeps every other blank's (the mistakes are graded in groups, no two in one blank and each
group's blanks every other one, so that each submission also holds correct blanks beside the wrong
ones: ``submissions.mistake_groups``, a third as many submissions as one per mistake), grades.csv says what the gradebook (read with SQL) holds,
every feedback page hides the hidden tests, and regrading gives every cell again. This is what
`python -m autograder demo` shows, asserted.

The labs are dealt into two halves of about as many submissions each (so that a new lab lands in
one of them without an edit), so that `pytest -n 2 --dist loadfile` grades the two halves on two
workers at once. A test file sets ``HALF`` and imports everything here (``__all__``): the tests,
the ``graded`` fixture, and the hook that parametrizes ``lab`` over its half; it marks its tests
``about(*HALF)`` (tests/over_labs.py), and with ``pytest --lab`` the fixtures grade the chosen labs only.
"""

from __future__ import annotations

import html
import re
from pathlib import Path

import pytest

from autograder import cells
from autograder.pipeline import grading, nbgrader_apps
from autograder.catalogues import submissions
from autograder.pipeline.grading import GradeRow
from autograder.labs import Lab
from autograder.catalogues.mistakes import catalogue
from autograder.hidden_tests.diagnosis import LEAD
from course.checks import NOT_WRITTEN
from gradebook_sql import csv_disagreements, read_csv, sheets
from over_labs import LABS, chosen



def _halves(labs: list[Lab]) -> tuple[list[Lab], list[Lab]]:
    """The labs in two halves of about as many submissions each (blank, solved, one per mistake):
    the largest lab first, each into the half with fewer so far."""
    halves: tuple[list[Lab], list[Lab]] = ([], [])
    size = {lab: 2 + len(submissions.mistake_groups(lab)) for lab in labs}
    for lab in sorted(labs, key=lambda lab: (-size[lab], lab.id)):
        min(halves, key=lambda half: sum(size[other] for other in half)).append(lab)
    return halves


HALVES = _halves(LABS)

__all__ = ["graded", "pytest_generate_tests", "test_blank_release_scores_zero", "test_solved_notebook_scores_full_marks",
           "test_each_mistake_loses_its_blank_and_only_its_blank", "test_grades_csv_matches_the_gradebook",
           "test_feedback_shows_messages_but_not_hidden_tests", "test_regrading_gives_every_cell_again",
           "test_no_honest_submission_is_flagged", "test_feedback_names_the_mistake_it_diagnoses"]


def pytest_generate_tests(metafunc):
    if "lab" in metafunc.fixturenames:
        half = metafunc.module.HALF
        metafunc.parametrize("lab", half, ids=[lab.id for lab in half])


@pytest.fixture(scope="module")
def graded(request, tmp_path_factory) -> tuple[dict[tuple[str, str], GradeRow], Path]:
    """The demo class of the module's half of the labs (those of them that ``pytest --lab`` chose),
    graded two at a time as `demo` does: (student, lab) -> GradeRow, and the course folder."""
    folder = tmp_path_factory.mktemp("round-trip")
    class_dir, workdir = folder / "class", folder / "course"
    submissions.write_class(chosen(request.config, request.module.HALF), class_dir, grouped=True)
    rows = grading.grade(class_dir, workdir, jobs=2).rows
    return {(row.student, row.lab): row for row in rows}, workdir


def test_blank_release_scores_zero(graded, lab: Lab) -> None:
    row = graded[0][(submissions.BLANK, lab.id)]
    assert row.auto_max > 0
    assert row.auto_score == 0, row.cells


def test_solved_notebook_scores_full_marks(graded, lab: Lab) -> None:
    row = graded[0][(submissions.SOLVED, lab.id)]
    points = {cells.grade_id(c): cells.meta(c)["points"] for c in cells.read(lab.source_notebook).cells
              if cells.is_autograded_test(c)}
    assert row.max_cells.keys() >= points.keys() and {c: row.max_cells[c] for c in points} == points
    assert row.auto_score == row.auto_max == sum(points.values()), (row.lost, row.reasons)


def test_each_mistake_loses_its_blank_and_only_its_blank(graded, lab: Lab) -> None:
    for student, mistakes in submissions.mistake_groups(lab).items():
        row = graded[0][(student, lab.id)]
        tests = {f"test_{m.blank}" for m in mistakes}
        assert set(row.lost) == tests, f"{student} ({[m.slug for m in mistakes]}) lost {row.lost}, because {row.reasons}"
        assert all(row.cells[test] == 0 for test in tests)
        assert row.auto_score == row.auto_max - sum(row.max_cells[test] for test in tests)
        assert all(row.reasons.get(test) for test in tests), f"{student}: no reason given for one of {tests}"


def test_grades_csv_matches_the_gradebook(graded) -> None:
    """grades.csv parsed back against the SQLite gradebook read with SQL (tests/gradebook_sql.py)."""
    rows, workdir = graded
    table, book = read_csv(workdir / "grades.csv"), sheets(nbgrader_apps.course_config(workdir).CourseDirectory.db_url)
    assert set(book) == set(rows) == set(table)
    assert csv_disagreements(table, book) == []


HIDDEN_CODE = re.compile(r"hidden_tests|BEGIN HIDDEN|END HIDDEN|import solutions|from solutions|solutions\.\w")


def test_feedback_shows_messages_but_not_hidden_tests(graded) -> None:
    """Every feedback page of the class, failing hidden tests included: no hidden-test code, and the
    reason each lost cell lost its points is on the page."""
    rows, workdir = graded
    for (student, lab_id), row in rows.items():
        page = nbgrader_apps.feedback_page(workdir, lab_id, student).read_text()
        text = html.unescape(re.sub(r"<[^>]*>", "", page))
        assert not HIDDEN_CODE.search(text), (student, HIDDEN_CODE.search(text))
        blanks = cells.blank_names(cells.read(Lab(lab_id).source_notebook))
        assert not any(f"check_{blank}(" in text for blank in blanks), student
        for cell, reason in row.reasons.items():
            message = reason.split(": ", 1)[1][:60]  # "AssertionError: <message>"
            assert message in text, (student, cell, message)
        if student == submissions.BLANK:
            assert NOT_WRITTEN in text


def test_regrading_gives_every_cell_again(graded, request, tmp_path) -> None:
    """The first group of catalogued mistakes of each lab (its other blanks are correct: both kinds of hidden
    verdict), and the solved notebook of the half's first lab, graded again in a new course: every field
    of every row (cells, maxima, penalty, notes, reasons) comes out the same,
    but for a diagnosis sentence. A diagnosis gives up when it would take the cell past its share of
    the cell's time limit (autograder/hidden_tests/diagnosis.py), which a loaded machine can make it
    do in one grading and not in the other (CI of stop 38: the class graded two workers at a time)."""
    rows, labs, class_dir = graded[0], chosen(request.config, request.module.HALF), tmp_path / "class"
    picked = {(submissions.SOLVED, lab): submissions.solved(lab) for lab in labs[:1]}
    for lab in labs:
        student, mistakes = next(iter(submissions.mistake_groups(lab).items()))
        picked[(student, lab)] = submissions.with_mistakes(lab, mistakes)
    for (student, lab), nb in picked.items():
        submissions.write(nb, class_dir, student, lab)
    again = {(row.student, row.lab): row for row in grading.grade(class_dir, tmp_path / "course", jobs=2).rows}
    first = {(student, lab.id): rows[(student, lab.id)] for student, lab in picked}
    assert again.keys() == first.keys()

    def field(row: GradeRow, name: str):
        value = getattr(row, name)
        if name == "diagnosed":  # recorded with the diagnosis sentence, and dropped with it
            return None
        return {cell: DIAGNOSIS.sub("", reason) for cell, reason in value.items()} if name == "reasons" else value

    assert [] == [(key, name, field(first[key], name), field(again[key], name)) for key in first
                  for name in vars(first[key]) if field(first[key], name) != field(again[key], name)]


DIAGNOSIS = re.compile(" " + re.escape(LEAD.split("{")[0]) + ".*")
"""The diagnosis sentence that ends a failure's message line, and the hint after it."""


def test_no_honest_submission_is_flagged(graded) -> None:
    flagged = {key: row.flags for key, row in graded[0].items() if row.flags}
    assert flagged == {}, "the integrity checks flagged honest work (the solved notebooks and every catalogued mistake)"


def test_feedback_names_the_mistake_it_diagnoses(graded, lab: Lab) -> None:
    """In grading (in the kernel, under the integrity monitor), the reason a mistake's cell lost its
    points gives that mistake's hint and no other mistake's (autograder/hidden_tests/diagnosis.py). All of them
    are named on an idle machine; a diagnosis that runs out of time is left out, so at least half."""
    named = 0
    student_of = {m.slug + m.blank: student for student, ms in submissions.mistake_groups(lab).items() for m in ms}
    for mistake in catalogue(lab):
        student = student_of[mistake.slug + mistake.blank]
        reason = graded[0][(student, lab.id)].reasons[f"test_{mistake.blank}"]
        others = [m.slug for m in catalogue(lab) if m.blank == mistake.blank and m is not mistake and m.hint in reason]
        assert others == [], f"{student} ({mistake.slug}) is diagnosed as {others}: {reason}"
        named += mistake.hint in reason
    assert named >= len(catalogue(lab)) / 2, f"only {named} of {len(catalogue(lab))} mistakes named in the feedback"

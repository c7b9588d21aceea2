"""Faulty submissions are graded alongside honest ones: each gets a clear reason, loses only what
its fault costs, and nobody else's grade changes (autograder/catalogues/faults.py has the catalogue)."""

import shutil

import pytest

from autograder import cells
from autograder.catalogues import faults, submissions, synthetic_class
from autograder.pipeline import grading, nbgrader_apps
from autograder.catalogues.faults import FAULTS
from autograder.hidden_tests.isolate import called_blanks
from autograder.labs import get_lab
from over_labs import about

LAB = get_lab("train-kf")
BLANK = "gain_information_form"
"""The blank that holds the faults: its visible checks and one demonstration cell call it too."""
pytestmark = about(LAB)


@pytest.fixture(scope="module")
def graded(tmp_path_factory, short_timeouts):
    """Grade the honest pair and every fault in one batch, three at a time (the stuck ones mostly
    wait), with 10 s cell timeouts."""
    class_dir = tmp_path_factory.mktemp("class")
    for student, nb in ((submissions.SOLVED, submissions.solved(LAB)), (submissions.BLANK, cells.read(LAB.release_notebook))):
        submissions.write(nb, class_dir, student, LAB)
    faults.write_faults(LAB, BLANK, class_dir)
    workdir = tmp_path_factory.mktemp("course")
    rows = grading.grade(class_dir, workdir, jobs=3).rows
    return {row.student: row for row in rows}, workdir, class_dir


@pytest.fixture(scope="module")
def short_timeouts():
    """Cell timeout of 10 s for this module's grading (the course's is 30 s)."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("GRADING_CELL_TIMEOUT", "10")
        yield


def test_honest_submissions_are_graded_normally(graded):
    graded, _, _ = graded
    assert graded[submissions.SOLVED].auto_score == graded[submissions.SOLVED].auto_max
    assert graded[submissions.SOLVED].notes == () and graded[submissions.SOLVED].reasons == {}
    assert graded[submissions.BLANK].auto_score == 0


@pytest.mark.parametrize("fault", FAULTS, ids=[f.slug for f in FAULTS])
def test_each_fault_costs_what_it_should_says_why_and_is_not_flagged(graded, fault):
    graded, _, _ = graded
    row = graded[fault.student_id(LAB)]
    assert synthetic_class.fault_outcome(LAB, fault, BLANK).errors(row) == [], (row.reasons, row.notes)
    said = " ".join([*(note.text for note in row.notes), *row.reasons.values()])
    assert fault.says in said, said


def test_feedback_shows_the_graders_note_first(graded):
    fault = faults.get("kernel-dies")
    _, workdir, _ = graded
    html = nbgrader_apps.feedback_page(workdir, LAB.id, fault.student_id(LAB)).read_text()
    assert html.index("Note from the grader") < html.index("Lab train-kf")
    assert "The kernel died in cell" in html


def test_a_blank_that_kills_its_kernel_costs_no_later_blank_that_calls_it(tmp_path):
    """Partial credit outlives a dead kernel: run_filter's reference calls predict, so run_filter's
    hidden test calls the reference's predict although predict's own test cell killed the kernel
    (before, such a fault also cost the later blank: castaway-bob's 200-submission class showed it)."""
    blank, fault = "predict", faults.get("kernel-dies")
    order = LAB.blanks()
    callers = [b for b in order[order.index(blank) + 1:] if blank in called_blanks(LAB.reference(), b, order)]
    assert callers, f"no blank after {blank} calls it: choose one that a later blank's reference calls"
    faults.write_fault(fault, LAB, blank, tmp_path / "class")
    [row] = grading.grade(tmp_path / "class", tmp_path / "course", jobs=1).rows
    assert synthetic_class.fault_outcome(LAB, fault, blank).errors(row) == [], (row.reasons, row.notes)
    assert all(row.cells[f"test_{b}"] > 0 for b in callers)


REGRADED = ("kernel-dies", "memory-hog", "numpy-warning", "reordered", "not-json")
"""The faults graded again: every kind of recovery and note except those that depend on the
machine's speed: the timeouts (whose 10 s stops would also double this module's time) and the loud
cell, whose 100 MB of output took more than the 10 s cell limit on a loaded machine (the regraded
row then carries one more note, and loses nothing)."""


def test_regrading_faults_gives_every_field_again_and_leaves_every_other_row_as_it_was(graded, tmp_path):
    """Some of the class graded again in the same course: the regraded rows come out the same in
    every field (cells, notes, reasons), and nobody else's row changes."""
    rows, workdir, class_dir = graded
    students = [f.student_id(LAB) for f in FAULTS if f.slug in REGRADED]
    assert len(students) == len(REGRADED)
    for student in students:
        shutil.copytree(class_dir / student, tmp_path / student)
    again = {row.student: row for row in grading.grade(tmp_path, workdir, jobs=3).rows}
    assert again == rows, "regrading changed a row (the regraded ones must come out the same too)"

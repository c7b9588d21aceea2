"""Faulty submissions are graded alongside honest ones: each gets a clear reason, loses only what
its fault costs, and nobody else's grade changes (autograder/faults.py has the catalogue)."""

import pytest

from autograder import faults, grading, submissions
from autograder.faults import ALL, FAULTS
from autograder.labs import get_lab
import nbformat

LAB = get_lab("train-kf")
BLANK = "gain_information_form"
"""The blank that holds the faults: its visible checks and one demonstration cell call it too."""


@pytest.fixture(scope="module")
def graded(tmp_path_factory, monkeypatch_module):
    """Grade the honest pair and every fault in one batch, with short cell timeouts."""
    class_dir = tmp_path_factory.mktemp("class")
    for student, nb in ((submissions.SOLVED, submissions.solved(LAB)), (submissions.BLANK, grading.cells.read(LAB.release_notebook))):
        path = class_dir / student / LAB.id / LAB.notebook_name
        path.parent.mkdir(parents=True)
        nbformat.write(nb, path)
    faults.write_faults(LAB, BLANK, class_dir)
    rows = grading.grade(class_dir, tmp_path_factory.mktemp("course"))
    return {row.student: row for row in rows}


@pytest.fixture(scope="module")
def monkeypatch_module():
    """Cell timeout of 10 s for this module's grading (the course's is 30 s)."""
    original = grading.course_config

    def shorter(workdir=grading.ROOT):
        config = original(workdir)
        config.Execute.timeout = 10
        return config

    grading.course_config = shorter
    yield
    grading.course_config = original


def test_honest_submissions_are_graded_normally(graded):
    assert graded[submissions.SOLVED].auto_score == graded[submissions.SOLVED].auto_max
    assert graded[submissions.SOLVED].notes == () and graded[submissions.SOLVED].reasons == {}
    assert graded[submissions.BLANK].auto_score == 0


@pytest.mark.parametrize("fault", FAULTS, ids=[f.slug for f in FAULTS])
def test_each_fault_costs_what_it_should_and_says_why(graded, fault):
    row = graded[fault.student_id(LAB)]
    solved = graded[submissions.SOLVED]
    expected_lost = {ALL: sorted(solved.autograded), "blank": [f"test_{BLANK}"], None: []}[fault.loses]
    assert sorted(row.lost) == expected_lost, (row.lost, row.reasons, row.notes)
    said = " ".join([*row.notes, *row.reasons.values()])
    assert fault.says in said, said


def test_feedback_carries_the_graders_note(graded, tmp_path):
    # The note is the first cell of the graded notebook, so the feedback shows it first.
    fault = next(f for f in FAULTS if f.slug == "kernel-dies")
    row = graded[fault.student_id(LAB)]
    assert any("The kernel died" in note for note in row.notes)

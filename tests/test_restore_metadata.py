"""A submission whose lab cells' nbgrader metadata was changed is graded as released.

One flag or key changed in one cell made nbgrader 0.9.6 fail on the whole submission ("not graded:
see the log", no row, no feedback): a test cell that says ``grade: false`` or ``solution: true``
(OverwriteCells: "Inconsistent checksums"), ``task: true`` ("Task cells have to be markdown"), an
answer cell that says ``grade: true``, a written answer that says ``grade: false``, or keys nbgrader's
schema lacks ("Additional properties are not allowed"). RestoreLabCells puts every lab cell's nbgrader
metadata back as released (autograder/pipeline/restore.py); the catalogued fault ``nbgrader-metadata``
grades all six in one submission end to end (tests/test_faults.py)."""

from __future__ import annotations

import pytest

from autograder import cells
from autograder.labs import get_lab
from autograder.pipeline.restore import grader_notes
from defended_runs import sanitized
from over_labs import about

TRAIN = get_lab("train-kf")
pytestmark = about(TRAIN)

EDITS = {
    "test_grade_false": ("test_nees", {"grade": False}),
    "test_solution_true": ("test_nees", {"solution": True}),
    "test_task_true": ("test_nees", {"task": True}),
    "answer_grade_true": ("nees", {"grade": True, "points": 5}),
    "written_grade_false": ("derivation_1", {"grade": False}),
    "stray_keys": ("test_nees", {"score": 1, "kit_note": "hi", "comment": "<b>x</b>"}),
}


@pytest.fixture(scope="module")
def course(tmp_path_factory):
    return tmp_path_factory.mktemp("course")


def _flags(cell) -> dict:
    return {k: v for k, v in cell.metadata["nbgrader"].items() if k != "checksum"}


@pytest.mark.parametrize("edit", EDITS)
def test_changed_nbgrader_metadata_is_put_back_as_released(course, edit):
    grade_id, change = EDITS[edit]
    nb = cells.read(TRAIN.release_notebook)
    [cell] = [c for c in nb.cells if cells.meta(c).get("grade_id") == grade_id]
    cell.metadata["nbgrader"].update(change)
    graded = sanitized(nb, TRAIN, course)  # nbgrader's OverwriteCells and CheckCellMetadata raised here
    # (a test cell's checksum is the gradebook's, of the source with its hidden test: OverwriteCells sets it)
    released = {cells.grade_id(c): _flags(c) for c in cells.read(TRAIN.release_notebook).cells if "grade_id" in cells.meta(c)}
    got = {cells.grade_id(c): _flags(c) for c in graded.cells if "grade_id" in cells.meta(c)}
    assert got == released
    assert any(f"nbgrader metadata of cells {grade_id} was not as released" in note.text for note in grader_notes(graded))


def test_the_release_itself_gets_no_note(course):
    assert grader_notes(sanitized(cells.read(TRAIN.release_notebook), TRAIN, course)) == []

"""The score of a test cell is the grader's verdict alone (autograder/pipeline/verdicts.py): whatever
a submission makes its kernel put in a test cell (a result value of any kind, a line on stderr, a
result from the display hook, a result message sent on the kernel's own channel) changes no score,
up or down, through ``python -m autograder grade`` and through plain ``nbgrader autograde``.

From the attacker's side, every lab's blank notebook with each forgery (autograder/catalogues/cheats.py,
``FORGED_SCORES``) scores 0 on every code blank; from the honest student's side, the solved notebook
with each forgery keeps full marks on every blank the integrity scan does not flag, and a flagged
blank costs what README says. Before the verdicts, a blank notebook with the two lines of
``forged-result-text`` scored full marks on every lab.
"""

from __future__ import annotations

import subprocess
import sys

import pytest

from autograder import cells
from autograder.catalogues import submissions
from autograder.catalogues.cheats import FORGED_SCORES, _add_cell_after_setup
from autograder.labs import ROOT, Lab
from autograder.pipeline import grading
from autograder.pipeline.audit import audit
from over_labs import LABS, about, chosen

HONEST_LAB = Lab("train-kf")
"""The lab whose solved notebook is graded with every forgery."""


def _forged(nb, name: str):
    return _add_cell_after_setup(nb, FORGED_SCORES[name])


def _tests(lab: Lab) -> dict[str, float]:
    """Test cell id -> points."""
    return {cells.grade_id(c): float(cells.meta(c)["points"]) for c in cells.read(lab.source_notebook).cells
            if cells.is_autograded_test(c)}


@pytest.fixture(scope="module")
def graded(request, tmp_path_factory):
    """Every chosen lab's blank notebook with each forgery, and train-kf's solved one with each, graded
    by ``grade`` two at a time: (student, lab) -> GradeRow."""
    folder = tmp_path_factory.mktemp("forged")
    for lab in chosen(request.config, LABS):
        for name in FORGED_SCORES:
            submissions.write(_forged(cells.read(lab.release_notebook), name), folder, f"blank-{name}", lab)
    if chosen(request.config, [HONEST_LAB]):
        for name in FORGED_SCORES:
            submissions.write(_forged(submissions.solved(HONEST_LAB), name), folder, f"solved-{name}", HONEST_LAB)
    workdir = tmp_path_factory.mktemp("course")
    rows = grading.grade(folder, workdir, jobs=2).rows
    return {(row.student, row.lab): row for row in rows}, workdir


@about(*LABS)
@pytest.mark.parametrize("name", FORGED_SCORES)
def test_a_blank_notebook_that_forges_its_score_scores_nothing(graded, request, name):
    for lab in chosen(request.config, LABS):
        row = graded[0][f"blank-{name}", lab.id]
        scores = {cell: row.cells[cell] for cell in _tests(lab)}
        assert set(scores.values()) == {0.0}, f"{lab.id}, {name}: {scores}"


@about(HONEST_LAB)
@pytest.mark.parametrize("name", FORGED_SCORES)
def test_a_solved_notebook_keeps_its_marks_whatever_its_kernel_shows(graded, request, name):
    if not chosen(request.config, [HONEST_LAB]):
        pytest.skip("train-kf is not among the labs chosen with --lab")
    row = graded[0][f"solved-{name}", HONEST_LAB.id]
    flagged = row.flags
    for cell, points in _tests(HONEST_LAB).items():
        # a flag that costs every blank (README: the scan's findings) takes them all; nothing else does
        want = 0.0 if any("every blank" in note for note in flagged) else points
        assert row.cells[cell] == want, f"{name}: {cell} scored {row.cells[cell]}, not {want} ({flagged})"


@about(*LABS)
def test_the_audit_finds_no_kernel_made_score_in_a_class_graded_by_this_version(graded):
    """``python -m autograder audit`` on the forgeries graded above: every recorded score is the
    grader's verdict (tests/test_audit.py shows it finding those of a version before the verdicts)."""
    suspects, unchecked = audit(graded[1])
    assert suspects == [] and unchecked == [], (suspects, unchecked)


@about(HONEST_LAB)
def test_plain_nbgrader_autograde_takes_the_verdict_too(tmp_path):
    """``nbgrader autograde`` with the kit's nbgrader_config.py: a blank notebook that returns text
    from every test cell scores 0."""
    course = tmp_path / "course"
    course.mkdir()
    (course / "source").symlink_to(ROOT / "source")
    nb = _forged(cells.read(HONEST_LAB.release_notebook), "forged-result-text")
    submissions.write(nb, course / "submitted", "mallory", HONEST_LAB)
    # run from the course root, as README says, so that nbgrader reads the kit's nbgrader_config.py;
    # the course folder is the temporary one
    nbgrader = [sys.executable, "-m", "nbgrader"]
    for args in (["generate_assignment", HONEST_LAB.id, "--force"], ["autograde", HONEST_LAB.id, "--student", "mallory"]):
        done = subprocess.run([*nbgrader, *args, f"--CourseDirectory.root={course}"], cwd=ROOT,
                              capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr[-3000:]
    from nbgrader.api import Gradebook

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}") as gradebook:
        submission = gradebook.find_submission_notebook(HONEST_LAB.id, HONEST_LAB.id, "mallory")
        scores = {grade.name: grade.auto_score for grade in submission.grades if grade.name in _tests(HONEST_LAB)}
    assert scores and set(scores.values()) == {0.0}, scores

"""``python -m autograder audit`` finds the test cells whose score came from the student's kernel in a
course folder graded by a version before the grader's verdicts (autograder/pipeline/audit.py).

``tests/fixtures/graded-before-verdicts`` is a course folder that commit 7b2487f graded (its gradebook
and autograded notebooks; the outputs of cells that are not test cells removed to keep it small):
alice submitted the solved train-kf notebook (9 of 9), bob the blank one (0), mallory the blank one
with a cell that makes every test cell show the text "full marks" (9 of 9 then), and trudy one that
shows 1e9 (nbgrader gave up on it, so it has no autograded notebook). tests/test_forged_scores.py
checks that a class graded by this version holds nothing for the audit to find.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from autograder.__main__ import main
from autograder.pipeline.audit import audit

FIXTURE = Path(__file__).parent / "fixtures" / "graded-before-verdicts"


def test_the_audit_lists_exactly_the_forged_cells_of_a_course_graded_before_the_verdicts(tmp_path):
    course = tmp_path / "course"
    shutil.copytree(FIXTURE, course)
    suspects, unchecked = audit(course)
    assert {s.student for s in suspects} == {"mallory"}
    assert {s.cell for s in suspects} == {"test_gain_information_form", "test_gain_covariance_form", "test_process_noise",
                                          "test_predict", "test_kupdate", "test_run_filter", "test_nees"}
    assert all(s.recorded > 0 and s.verdict == 0 and "full marks" in s.shown for s in suspects), suspects
    assert unchecked == [("trudy", "train-kf")]


def test_the_audit_command_names_the_submissions_to_regrade_and_fails(tmp_path, capsys):
    course = tmp_path / "course"
    shutil.copytree(FIXTURE, course)
    assert main(["audit", "--workdir", str(course)]) == 1
    out = capsys.readouterr().out
    assert "mallory train-kf:" in out and "test_kupdate: recorded 2, the grader's verdict 0" in out
    assert "alice" not in out and "bob" not in out and "trudy train-kf: no autograded notebook" in out
    assert "1 graded submission with test cells whose score came from the student's kernel" in out

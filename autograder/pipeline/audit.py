"""``python -m autograder audit``: the graded test cells whose score could have come from the
student's kernel, in a course folder graded by a version of the kit before the grader's verdicts.

Before autograder/pipeline/verdicts.py, nbgrader read each test cell's score from its outputs, and
a submission's kernel could put an output there (a result value, a line on stderr) that decided the
score (README: Versions that graded wrongly). The grader's own verdict is still in the autograded
notebook: the grader wrote an error into a test cell whenever the hidden test failed, was stopped
or was not run. So a test cell whose score in the gradebook is not what that verdict gives (its
points with no error or stderr output in the cell, 0 with one) had its score shaped by the kernel:
regrade that submission. A cell graded by this version always agrees (the kernel's outputs there
are made unable to score). Manual scores given in formgrader are left out: they override both.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import nbformat
from nbgrader.api import Gradebook
from nbgrader.coursedir import CourseDirectory

from autograder import cells
from autograder.pipeline.nbgrader_apps import course_config
from course.checks import count


@dataclass(frozen=True)
class Suspect:
    """A test cell whose recorded score is not the grader's verdict."""

    student: str
    lab: str
    cell: str
    recorded: float
    verdict: float
    shown: str
    """The kernel's output that nbgrader read first, in words."""


def _verdict(cell, points: float) -> float:
    """The score the grader's verdict gives a test cell of an autograded notebook."""
    failed = any(o.output_type == "error" or (o.output_type == "stream" and o.get("name") == "stderr")
                 for o in cell.outputs)
    return 0.0 if failed else points


def _shown(cell) -> str:
    """The first output of the cell that nbgrader reads as a score, in words."""
    for output in cell.outputs:
        if output.output_type == "execute_result":
            return f"a result value, {str(output.get('data', {}).get('text/plain', ''))[:40]}"
        if output.output_type == "error":
            return f"an error, {output.get('ename', '')}"
        if output.output_type == "stream" and output.get("name") == "stderr":
            return "a line on stderr"
    return "no output that scores (full points)"


def audit(workdir: Path) -> tuple[list[Suspect], list[tuple[str, str]]]:
    """(the test cells whose recorded score is not the grader's verdict, the (student, lab) graded
    submissions that have no autograded notebook in ``workdir`` to check)."""
    suspects: list[Suspect] = []
    unchecked: list[tuple[str, str]] = []
    with Gradebook(CourseDirectory(config=course_config(workdir)).db_url) as gradebook:
        for assignment in gradebook.assignments:
            for submission in assignment.submissions:
                student = submission.student.id
                for notebook in submission.notebooks:
                    path = workdir / "autograded" / student / assignment.name / f"{notebook.name}.ipynb"
                    if not path.exists():
                        unchecked.append((student, assignment.name))
                        continue
                    by_id = {cells.grade_id(c): c for c in nbformat.read(path, as_version=4).cells
                             if cells.is_autograded_test(c)}
                    for grade in notebook.grades:
                        cell = by_id.get(grade.name)
                        if cell is None or grade.auto_score is None or grade.manual_score is not None:
                            continue
                        verdict = _verdict(cell, float(grade.max_score))
                        if abs(float(grade.auto_score) - verdict) > 1e-9:
                            suspects.append(Suspect(student, assignment.name, grade.name, float(grade.auto_score),
                                                    verdict, _shown(cell)))
    return suspects, unchecked


def run_audit(workdir: Path) -> int:
    """Print the suspect cells, grouped by submission; 1 if there are any, else 0."""
    suspects, unchecked = audit(workdir)
    by_submission: dict[tuple[str, str], list[Suspect]] = {}
    for suspect in suspects:
        by_submission.setdefault((suspect.student, suspect.lab), []).append(suspect)
    for (student, lab), found in sorted(by_submission.items()):
        print(f"{student} {lab}:")
        for s in found:
            print(f"  {s.cell}: recorded {s.recorded:g}, the grader's verdict {s.verdict:g} (the cell showed {s.shown} first)")
    for student, lab in sorted(set(unchecked)):
        print(f"{student} {lab}: no autograded notebook in {workdir / 'autograded'}, so it could not be checked")
    if by_submission:
        print(f"{count(len(by_submission), 'graded submission')} with test cells whose score came from the student's "
              "kernel, not from the grader's verdict. Regrade them with this version: put each in a SUBMISSIONS folder of "
              "its own and run `python -m autograder grade SUBMISSIONS` (the other grades stay as they are).")
        return 1
    print("Every graded test cell's score is the grader's verdict." if not unchecked else
          "Every test cell that could be checked has the grader's verdict as its score.")
    return 1 if unchecked else 0

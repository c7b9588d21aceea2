"""The grader's verdict on each autograded test cell: the one thing its score is made of.

nbgrader scores a test cell from its outputs (STACK.md): the first error or stderr stream gives 0,
the first result value is read as the score, and anything else is full marks. Whatever a student's
kernel can put in a graded cell would then be part of the score. Here it is not, by construction:

- ``GradingExecute`` records a ``Verdict`` per test cell in the grader's process, in nbgrader's
  ``resources`` (never in the notebook): passed when the hidden test's check ran to its end on the
  student's function without failing, and failed otherwise (the check failed, the cell was
  stopped or not run, the kernel died, the function warned); ``FlagCheating`` records a failure for
  every blank a finding games.
- ``GraderScores`` (in place of nbgrader's SaveAutoGrades) writes each test cell's score to the
  gradebook from that verdict alone: its points if it passed, 0 otherwise, and 0 for a test cell
  with no verdict. It never reads an output.
- What the kernel showed in a test cell stays visible to the student, but every such output is
  turned into one that cannot score (``display_only``): a result becomes displayed data, an error
  or stderr becomes stdout text. The only error in a test cell is then the grader's own, so
  nbgrader's own reading of the cell (``determine_grade``, in any tool that still reads it) gives
  the same score as the verdict.
- When a failing check's diagnosis names a catalogued mistake (autograder/hidden_tests/diagnosis.py),
  ``record_diagnosis`` writes its slug into the test cell's metadata (``DIAGNOSIS_KEY``) in the
  grader's process, and ``forget_diagnoses`` first removes any such key the submission brought: the
  autograded notebook then holds the diagnosis as data, beside the grader's notes, which survives
  sharding (it travels with autograded/) and is replaced when the submission is regraded. The kernel
  sends outputs only, never a cell's metadata, so nothing it emits decides a diagnosis.
- ``record_wrong_only`` writes likewise the kind of case that alone a failing hidden test was wrong on,
  when a property of its cases splits them exactly (autograder/hidden_tests/case_kinds.py,
  ``WRONG_ONLY_KEY``): the class report groups the failures that no catalogued mistake explains by it.
- ``record_visible_checks`` marks, in the same way, each visible check cell (``check_<blank>``) whose
  run in the grading kernel ended in an error (``VISIBLE_CHECK_KEY``): the class report counts the
  submissions handed in with failing visible checks. That is information for the instructor and
  never part of a score. It is read from the kernel's outputs, so a submission can make its own
  check cells fail or pass; that is harmless here, as nothing is decided by it.
"""

from __future__ import annotations

from dataclasses import dataclass

from nbformat import NotebookNode
from nbformat.v4 import new_output
from nbgrader.preprocessors import SaveAutoGrades

from autograder import cells

RESOURCES_KEY = "kit_verdicts"
"""Where the verdicts are kept in nbgrader's resources: grade id -> Verdict."""


@dataclass(frozen=True)
class Verdict:
    """The grader's verdict on one test cell, and in a sentence why it failed."""

    passed: bool
    why: str = ""


def record(resources: dict, grade_id: str, passed: bool, why: str = "") -> None:
    """Record the verdict on the test cell ``grade_id``; a failure is never overturned by a later pass."""
    verdicts = resources.setdefault(RESOURCES_KEY, {})
    earlier = verdicts.get(grade_id)
    if earlier is not None and not earlier.passed:
        return
    verdicts[grade_id] = Verdict(passed, why)


def verdict(resources: dict, grade_id: str) -> Verdict | None:
    """The recorded verdict on the test cell ``grade_id``, or None if the grader recorded none."""
    return resources.get(RESOURCES_KEY, {}).get(grade_id)


DIAGNOSIS_KEY = "autograder_diagnosis"
"""The key of a test cell's metadata, in the autograded notebook, that holds the diagnosed mistake's slug."""


WRONG_ONLY_KEY = "autograder_wrong_only"
"""The key of a test cell's metadata, in the autograded notebook, that holds the kind of case alone wrong."""
VISIBLE_CHECK_KEY = "autograder_visible_check_failed"
"""The key of a visible check cell's metadata, in the autograded notebook, set (True) when it raised."""


def forget_diagnoses(nb: NotebookNode) -> None:
    """Remove every diagnosis and visible check record from ``nb``'s cells: only the grader writes
    them, while it grades."""
    for cell in nb.cells:
        for key in (DIAGNOSIS_KEY, WRONG_ONLY_KEY, VISIBLE_CHECK_KEY):
            cell.metadata.pop(key, None)


def record_diagnosis(cell: NotebookNode, slug: str) -> None:
    """Record in the test cell ``cell`` that its hidden test failed as the catalogued mistake ``slug``."""
    cell.metadata[DIAGNOSIS_KEY] = slug


def record_wrong_only(cell: NotebookNode, cases: str) -> None:
    """Record in the test cell ``cell`` that its hidden test was wrong only on the cases with ``cases``."""
    cell.metadata[WRONG_ONLY_KEY] = cases


def diagnoses(nb: NotebookNode, key: str = DIAGNOSIS_KEY) -> dict[str, str]:
    """Test cell id -> the slug of the catalogued mistake diagnosed there (``key`` WRONG_ONLY_KEY: the
    kind of case alone wrong there), in an autograded notebook."""
    return {cells.grade_id(c): c.metadata[key] for c in nb.cells
            if cells.is_autograded_test(c) and isinstance(c.metadata.get(key), str)}


def record_visible_checks(nb: NotebookNode, not_run: str) -> None:
    """Mark each visible check cell of the executed ``nb`` that holds an error, other than the
    grader's ``not_run`` (a cell left unrun is no failed check): a stopped cell and a dead kernel count."""
    for cell in nb.cells:
        if cells.is_visible_check(cell) and any(o.output_type == "error" and o.get("ename") != not_run
                                                for o in cell.outputs):
            cell.metadata[VISIBLE_CHECK_KEY] = True


def visible_checks_failed(nb: NotebookNode) -> set[str]:
    """The test cells (``test_<blank>``) whose blank's visible checks failed, in an autograded notebook."""
    return {"test_" + cells.grade_id(c).removeprefix(cells.CHECK_PREFIX) for c in nb.cells
            if cells.is_visible_check(c) and c.metadata.get(VISIBLE_CHECK_KEY) is True}


def display_only(output: NotebookNode) -> NotebookNode:
    """A kernel's output as one that nbgrader cannot read as a score: a result as displayed data,
    an error or stderr as stdout text; displayed data and stdout as they are."""
    kind = output.get("output_type")
    if kind == "execute_result":
        return new_output("display_data", data=dict(output.get("data", {})), metadata=dict(output.get("metadata", {})))
    if kind == "error":
        lines = output.get("traceback") or [f"{output.get('ename', '')}: {output.get('evalue', '')}"]
        return new_output("stream", name="stdout", text="\n".join(str(line) for line in lines) + "\n")
    if kind == "stream":
        return new_output("stream", name="stdout", text=str(output.get("text", "")))
    return output  # displayed data


class GraderScores(SaveAutoGrades):
    """nbgrader's SaveAutoGrades, with each autograded test cell scored from the grader's verdict
    alone (see the module doc); written answers are left to nbgrader (and the hand grader)."""

    def _add_score(self, cell: NotebookNode, resources: dict) -> None:
        if not cells.is_autograded_test(cell):
            return super()._add_score(cell, resources)
        grade_id = cells.grade_id(cell)
        grade = self.gradebook.find_grade(grade_id, self.notebook_id, self.assignment_id, self.student_id)
        found = verdict(resources, grade_id)
        if found is None:
            self.log.error("The grader recorded no verdict for test cell %s of %s; it scores 0.", grade_id,
                           self.student_id)
        grade.auto_score = float(cell.metadata["nbgrader"]["points"]) if found is not None and found.passed else 0.0
        grade.needs_manual_grade = grade.manual_score is not None
        self.gradebook.db.commit()

"""Taking away the points that a dishonest submission games, and flagging it for review.

Runs right after GradingExecute and before nbgrader saves the scores. It scans the submission's
code (autograder/integrity/scan.py, in a child process capped in CPU time and memory:
autograder/integrity/confined.py), records a failing verdict for the test cell of every blank a finding
games (autograder/pipeline/verdicts.py: the score is 0 whatever the kernel showed), shows the reason
there as an error, and writes each reason as a "Flagged
for review" note at the top of the notebook, where the instructor's table and the feedback show it.
"""

from __future__ import annotations

from nbformat import NotebookNode
from nbformat.v4 import new_output
from nbgrader.preprocessors import NbGraderPreprocessor

from autograder import cells
from autograder.integrity.confined import confined_findings
from autograder.integrity.scan import Finding
from autograder.labs import Lab
from autograder.pipeline import verdicts
from autograder.pipeline.restore import NoteKind, add_grader_notes

FLAG = "Flagged for review:"
ERROR_NAME = "FlaggedForReview"


class FlagCheating(NbGraderPreprocessor):
    """Zero the test cells of the blanks that integrity findings say are gamed; note the reasons."""

    def preprocess(self, nb: NotebookNode, resources: dict) -> tuple[NotebookNode, dict]:
        lab = Lab(resources["nbgrader"]["assignment"])
        findings: list[Finding] = []
        for finding in confined_findings(nb, lab):
            if finding.reason not in [f.reason for f in findings]:
                findings.append(finding)
        blanks = cells.blank_names(cells.read(lab.source_notebook))
        gamed: dict[str, list[str]] = {}
        for finding in findings:
            for blank in blanks if finding.blanks is None else finding.blanks:
                gamed.setdefault(f"test_{blank}", []).append(finding.reason)
        for cell in nb.cells:
            if cell.cell_type == "code" and "grade_id" in cells.meta(cell) and cells.grade_id(cell) in gamed:
                why = " ".join(gamed[cells.grade_id(cell)])
                verdicts.record(resources, cells.grade_id(cell), passed=False, why=why)
                cell.outputs.append(new_output("error", ename=ERROR_NAME, evalue=f"This test was not counted. {why}",
                                               traceback=[f"{ERROR_NAME}: This test was not counted. {why}"]))
        add_grader_notes(nb, [f"{FLAG} {f.reason.rstrip('.')}. {_cost(f)}" for f in findings], NoteKind.FLAG)
        return nb, resources


def _cost(finding: Finding) -> str:
    """What a finding costs, as the sentence that follows its reason."""
    if finding.blanks is None:
        return "It costs the points of every blank."
    if not finding.blanks:
        return "It costs no points."
    return "It costs the points of " + ", ".join(finding.blanks) + "."

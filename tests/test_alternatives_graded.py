"""The bank of correct alternatives graded through ``grade`` (issue 30: in-process and through the round
trip), where partial credit depends on the grader serving an earlier blank to a later one only on the
calls that the reference makes (autograder/pipeline/served_calls.py).

Per lab and k = 0, 1, 2: submission ``alt-k`` holds every blank's k-th alternative (the last one where
a blank has fewer) and keeps full marks on every blank; ``alt-k-with-mistakes`` is the same with every
blank that another blank's reference calls holding its first catalogued mistake instead: exactly those
blanks lose their points, and the alternatives that call them keep theirs. A fairness review found two
ways a correct caller lost its points to a wrong callee (an argument passed by position, an info dict
holding other entries); both are calls an alternative makes.
"""

from __future__ import annotations

import pytest

from autograder import cells
from autograder.catalogues import submissions
from autograder.catalogues.alternatives import catalogue as alternatives
from autograder.catalogues.mistakes import catalogue as mistakes
from autograder.hidden_tests.isolate import called_blanks
from autograder.labs import Lab
from autograder.pipeline import grading
from over_labs import LABS, about, chosen

KS = (0, 1, 2)


def _called(lab: Lab) -> set[str]:
    """The blanks that another blank's reference calls (the grader serves them)."""
    blanks, reference = lab.blanks(), lab.reference()
    return {name for blank in blanks for name in called_blanks(reference, blank, blanks)}


def _submission(lab: Lab, k: int, with_mistakes: bool):
    nb = submissions.solved(lab)
    model = cells.model_answers(cells.read(lab.source_notebook))
    bank = alternatives(lab)
    wrong = {m.blank: m for m in reversed(mistakes(lab))} if with_mistakes else {}
    for cell in nb.cells:
        if not cells.is_code_answer(cell):
            continue
        blank = cells.grade_id(cell)
        if blank in wrong and blank in _called(lab):
            cell.source = wrong[blank].apply(model[blank])
        else:
            mine = [a for a in bank if a.blank == blank]
            cell.source = mine[min(k, len(mine) - 1)].code
    return nb


@pytest.fixture(scope="module")
def graded(request, tmp_path_factory):
    folder = tmp_path_factory.mktemp("alternatives")
    for lab in chosen(request.config, LABS):
        for k in KS:
            submissions.write(_submission(lab, k, False), folder, f"alt-{k}", lab)
            submissions.write(_submission(lab, k, True), folder, f"alt-{k}-with-mistakes", lab)
    rows = grading.grade(folder, tmp_path_factory.mktemp("course"), jobs=2).rows
    return {(row.student, row.lab): row for row in rows}


@about(*LABS)
@pytest.mark.parametrize("k", KS)
def test_every_alternative_keeps_full_marks_through_grade(graded, request, k):
    for lab in chosen(request.config, LABS):
        row = graded[f"alt-{k}", lab.id]
        assert row.lost == [], f"{lab.id}, alternatives #{k}: lost {row.lost}: {row.reasons}"
        assert not row.flags, f"{lab.id}, alternatives #{k} is flagged: {row.flags}"


@about(*LABS)
@pytest.mark.parametrize("k", KS)
def test_alternatives_that_call_a_wrong_blank_keep_their_points(graded, request, k):
    for lab in chosen(request.config, LABS):
        row = graded[f"alt-{k}-with-mistakes", lab.id]
        wrong = {f"test_{blank}" for blank in _called(lab)}
        assert set(row.lost) == wrong, (f"{lab.id}, alternatives #{k} with the served blanks wrong: lost "
                                        f"{sorted(row.lost)}, not {sorted(wrong)}: {row.reasons}")

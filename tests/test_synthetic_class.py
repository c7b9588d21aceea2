"""The mixed synthetic class that the throughput benchmark grades: what it holds, and how a graded
row is checked against its catalogued outcome."""

import pytest

from autograder.catalogues import cheats, faults, synthetic_class
from autograder.integrity.flag import FLAG
from autograder.pipeline.grading import GradeRow
from autograder.pipeline.restore import GraderNote, NoteKind
from autograder.labs import get_lab
from autograder.catalogues.synthetic_class import CHEAT, FAULT, MISTAKE, SOLVED, Outcome

LAB = get_lab("train-kf")


def test_a_class_holds_every_fault_and_cheat_then_honest_work(tmp_path):
    outcomes = synthetic_class.write(LAB, 60, tmp_path)
    kinds = [o.kind for o in outcomes]
    assert kinds.count(FAULT) == len(faults.FAULTS) and kinds.count(CHEAT) == len(cheats.catalogue(LAB))
    assert kinds.count(SOLVED) >= 1 and kinds.count(MISTAKE) >= 1 and len(outcomes) == 60
    assert sorted(p.parts[-3] for p in tmp_path.glob("*/train-kf/*")) == sorted(o.student for o in outcomes)


def test_a_class_too_small_for_its_hostile_work_is_refused(tmp_path):
    with pytest.raises(ValueError, match="at least"):
        synthetic_class.write(LAB, 10, tmp_path)


def _row(scores: dict[str, float], notes: tuple[GraderNote, ...] = ()) -> GradeRow:
    return GradeRow("s", LAB.id, dict(scores), {c: 1.0 for c in scores}, frozenset(scores), notes=notes)


@pytest.mark.parametrize("scores, notes, expected", [
    ({"test_a": 1, "test_b": 1}, (), []),
    ({"test_a": 0, "test_b": 1}, (), ["s: test_a lost marks (no reason)"]),
    ({"test_a": 1, "test_b": 1}, (GraderNote(NoteKind.FLAG, f"{FLAG} it read the reference"),), ["s: flagged: ['it read the reference']"]),
])
def test_honest_work_must_keep_its_marks_and_stay_unflagged(scores, notes, expected):
    assert Outcome("s", SOLVED, (), only=True, flagged=False).errors(_row(scores, notes)) == expected


def test_a_cheat_must_score_zero_on_what_it_games_and_be_flagged():
    cheat = Outcome("s", CHEAT, ("test_a",), only=False, flagged=True)
    assert cheat.errors(_row({"test_a": 0, "test_b": 0}, (GraderNote(NoteKind.FLAG, f"{FLAG} x"),))) == []
    assert cheat.errors(_row({"test_a": 1, "test_b": 1})) == ["s: test_a scored 1, not 0", "s: not flagged"]
    everything = Outcome("s", CHEAT, None, only=False, flagged=True)
    assert everything.errors(_row({"test_a": 0, "test_b": 0.5}, (GraderNote(NoteKind.FLAG, f"{FLAG} x"),))) == ["s: test_b scored 0.5, not 0"]


def test_a_missing_row_is_an_error():
    assert synthetic_class.errors([], [Outcome("s", SOLVED, (), only=True, flagged=False)]) == {"s": ["s: no grade"]}

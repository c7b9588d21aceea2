"""Dishonest submissions, graded by the real pipeline alongside an honest one: each earns nothing
for the blanks it games, and each that the integrity checks catch is flagged with its reason
(autograder/cheats.py has the catalogue; tests/test_integrity.py tests the detector itself)."""

import nbformat
import pytest

from autograder import cheats, grading, submissions
from autograder.cheats import RUNTIME, STATIC
from autograder.labs import get_lab

LAB = get_lab("train-kf")
CHEATS = [c for c in cheats.catalogue(LAB)]


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    class_dir = tmp_path_factory.mktemp("class")
    for student, nb in [(submissions.SOLVED, submissions.solved(LAB))] + [(c.name, c.notebook(LAB)) for c in CHEATS]:
        path = class_dir / student / LAB.id / LAB.notebook_name
        path.parent.mkdir(parents=True)
        nbformat.write(nb, path)
    rows = grading.grade(class_dir, tmp_path_factory.mktemp("course"), jobs=2)
    return {row.student: row for row in rows}


def test_the_honest_submission_keeps_full_marks_and_is_not_flagged(graded):
    row = graded[submissions.SOLVED]
    assert row.auto_score == row.auto_max and row.flags == []


@pytest.mark.parametrize("cheat", CHEATS, ids=[c.name for c in CHEATS])
def test_a_cheat_earns_nothing_for_what_it_games_and_is_flagged(graded, cheat):
    row = graded[cheat.name]
    gamed = cheat.blanks(LAB)
    tests = sorted(row.autograded) if gamed is None else [f"test_{blank}" for blank in gamed]
    assert all(row.cells[t] == 0 for t in tests), {t: row.cells[t] for t in tests}
    if cheat.caught_by & {STATIC, RUNTIME}:
        assert row.flags, f"{cheat.name} was not flagged: {row.notes}"
    else:  # defeated without a flag: restored test cells, or the hidden tests' random inputs
        assert row.flags == [], row.flags

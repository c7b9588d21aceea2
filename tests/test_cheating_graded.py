"""Dishonest submissions, graded by the real pipeline alongside honest ones: each earns nothing
for the blanks it games, and each that the integrity checks catch is flagged with its reason
(autograder/cheats.py has the catalogue; tests/test_integrity.py tests the detector itself).

Every train-kf cheat is graded. In the other labs, the cheats that the static scan catches go
through the same lab-independent flagging as train-kf's (test_integrity.py checks the scan on every
lab), so only those that must be stopped while the notebook runs or by the sanitize step are
graded here; benchmarks/grading_throughput.py grades every cheat of every lab.
"""

import html
import re

import pytest

from autograder import cheats, grading, submissions, synthetic_class
from autograder.cheats import STATIC
from autograder.flag_cheating import FLAG
from autograder.labs import all_labs, get_lab

TRAIN = get_lab("train-kf")
CASES = [(TRAIN, cheat) for cheat in cheats.catalogue(TRAIN)] + [
    (lab, cheat) for lab in all_labs() if lab != TRAIN for cheat in cheats.catalogue(lab) if STATIC not in cheat.caught_by
]


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    class_dir = tmp_path_factory.mktemp("class")
    honest = [(submissions.SOLVED, lab, submissions.solved(lab)) for lab in all_labs()]
    for student, lab, nb in honest + [(cheat.name, lab, cheat.notebook(lab)) for lab, cheat in CASES]:
        submissions.write(nb, class_dir, student, lab)
    workdir = tmp_path_factory.mktemp("course")
    rows = grading.grade(class_dir, workdir, jobs=2)
    return {(row.student, row.lab): row for row in rows}, workdir


@pytest.mark.parametrize("lab", all_labs(), ids=lambda lab: lab.id)
def test_the_honest_submission_keeps_full_marks_and_is_not_flagged(graded, lab):
    rows, _ = graded
    row = rows[(submissions.SOLVED, lab.id)]
    assert row.auto_score == row.auto_max and row.flags == []


@pytest.mark.parametrize("lab, cheat", CASES, ids=[f"{lab.id}-{cheat.name}" for lab, cheat in CASES])
def test_a_cheat_earns_nothing_for_what_it_games_and_is_flagged_when_caught(graded, lab, cheat):
    rows, _ = graded
    assert synthetic_class.cheat_outcome(lab, cheat).errors(rows[(cheat.name, lab.id)]) == []


def test_the_feedback_shows_each_flag_as_written(graded):
    """Reasons name code such as ``__import__``, which Markdown would otherwise show as bold "import"."""
    rows, workdir = graded
    flagged = [row for row in rows.values() if row.flags]
    assert any("__import__" in flag for row in flagged for flag in row.flags)
    for row in flagged:
        page = (workdir / "feedback" / row.student / row.lab / f"{row.lab}.html").read_text()
        text = html.unescape(re.sub(r"<[^>]*>", "", page))
        for flag in row.flags:
            assert f"{FLAG} {flag}" in text, (row.student, flag)

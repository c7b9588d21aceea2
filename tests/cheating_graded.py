"""Dishonest submissions, graded by the real pipeline alongside honest ones: the tests that
tests/test_cheating_graded.py (every cheat of train-kf) and tests/test_cheating_graded_other_labs.py
(the other labs) both run, each on its own class (autograder/catalogues/cheats.py has the catalogue;
tests/test_integrity.py tests the detector itself).

Each cheat earns nothing for the blanks it games, and each that the integrity checks catch is
flagged with its reason, on its feedback page too; the honest submissions keep full marks; and a
sample of the cheats graded again in a new course comes out the same in every field. A test file
sets ``CASES`` ((lab, cheat) pairs) and ``HONEST`` (labs whose solved notebook is graded alongside),
marks its tests ``about`` those labs (tests/over_labs.py), and imports everything here (``__all__``).
With ``pytest --lab`` only the chosen labs' submissions are graded.
"""

from __future__ import annotations

import html
import re

import pytest

from autograder.pipeline import grading, nbgrader_apps
from autograder.catalogues import submissions, synthetic_class
from autograder.integrity.flag import FLAG
from over_labs import chosen

__all__ = ["graded", "pytest_generate_tests", "test_the_honest_submission_keeps_full_marks_and_is_not_flagged",
           "test_a_cheat_earns_nothing_for_what_it_games_and_is_flagged_when_caught",
           "test_the_feedback_shows_each_flag_as_written", "test_regrading_cheats_gives_every_field_again"]


def pytest_generate_tests(metafunc):
    if "lab" in metafunc.fixturenames and "cheat" in metafunc.fixturenames:
        cases = metafunc.module.CASES
        metafunc.parametrize("lab, cheat", cases, ids=[f"{lab.id}-{cheat.name}" for lab, cheat in cases])
    elif "lab" in metafunc.fixturenames:
        metafunc.parametrize("lab", metafunc.module.HONEST, ids=[lab.id for lab in metafunc.module.HONEST])


def _chosen(request) -> tuple[list, list]:
    """The module's CASES and HONEST, of the labs that ``pytest --lab`` chose."""
    return ([(lab, cheat) for lab, cheat in request.module.CASES if chosen(request.config, [lab])],
            chosen(request.config, request.module.HONEST))


def _write(cases, honest, folder):
    for lab in honest:
        submissions.write(submissions.solved(lab), folder, submissions.SOLVED, lab)
    for lab, cheat in cases:
        submissions.write(cheat.notebook(lab), folder, cheat.name, lab)


@pytest.fixture(scope="module")
def graded(request, tmp_path_factory):
    """The module's class graded two at a time: (student, lab) -> GradeRow, and the course folder."""
    class_dir = tmp_path_factory.mktemp("class")
    _write(*_chosen(request), class_dir)
    workdir = tmp_path_factory.mktemp("course")
    rows = grading.grade(class_dir, workdir, jobs=2).rows
    return {(row.student, row.lab): row for row in rows}, workdir


def test_the_honest_submission_keeps_full_marks_and_is_not_flagged(graded, lab):
    row = graded[0][(submissions.SOLVED, lab.id)]
    assert row.auto_score == row.auto_max and row.flags == []


def test_a_cheat_earns_nothing_for_what_it_games_and_is_flagged_when_caught(graded, lab, cheat):
    assert synthetic_class.cheat_outcome(lab, cheat).errors(graded[0][(cheat.name, lab.id)]) == []


def test_the_feedback_shows_each_flag_as_written(graded, request):
    """Reasons name code such as ``__import__``, which Markdown would otherwise show as bold "import"."""
    rows, workdir = graded
    flagged = [row for row in rows.values() if row.flags]
    assert flagged
    if any(cheat.name == "dunder-import-reference" for _, cheat in _chosen(request)[0]):
        assert any("__import__" in flag for row in flagged for flag in row.flags)
    for row in flagged:
        page = nbgrader_apps.feedback_page(workdir, row.lab, row.student).read_text()
        text = html.unescape(re.sub(r"<[^>]*>", "", page))
        for flag in row.flags:
            assert f"{FLAG} {flag}" in text, (row.student, flag)


def test_regrading_cheats_gives_every_field_again(graded, request, tmp_path):
    """One cheat of each way of being caught (the static scan, the grader's comparison, the sandbox,
    the sanitize step, the hidden tests), graded again in a new course: every field of its row
    (cells, penalty, notes with the flags, reasons) is the same."""
    cases = _chosen(request)[0]
    ways = sorted({way for _, cheat in cases for way in cheat.caught_by})
    again_cases = []
    for way in ways:  # the first cheat caught that way, preferring one caught only that way
        again_cases += [min((case for case in cases if way in case[1].caught_by), key=lambda case: len(case[1].caught_by))]
    again_cases = list(dict.fromkeys(again_cases))
    _write(again_cases, [], tmp_path / "class")
    again = {(row.student, row.lab): row for row in grading.grade(tmp_path / "class", tmp_path / "course", jobs=2).rows}
    assert again == {(c.name, lab.id): graded[0][(c.name, lab.id)] for lab, c in again_cases}

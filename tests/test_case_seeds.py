"""Every hidden check is right on every submission seed, not only on the default one.

The grader draws each submission's hidden cases from a seed of its own (autograder/hidden_tests/cases.py),
so every seed is one a student can get: on the default seed and 50 others (``CASE_SEEDS``), the reference and the
notebook's model answer (as ``define`` compiles it) pass every blank's hidden check, and every
catalogued mistake (``mistakes.py``) fails its own blank's check the way its entry says (the hidden
test's AssertionError, or the exception named by ``raises``). The diagnosis is left out
(``check.__wrapped__``): it re-raises the same exception, and tests/test_diagnosis.py tests it.

One item per lab and blank (the correct answers) and per mistake; a failure lists the seeds it
fails on.

Cost, the whole file on one worker of the shared 2-core machine at a load average of about 6.5 (fair-a):
140 s, of which train-kf 3 s, castaway-bob 11 s, nonlinear-filters 51 s, reentry-pf 51 s and reentry-srekf
24 s (the reentry labs before their checks draw from the submission seed). nonlinear-filters' bootstrap_pf_step
check, with its 100,000-particle noise test, takes about 0.4 s per seed and answer: 41 s of its lab's 51 s
go to the reference and the model answer on 51 seeds, so its mistakes, like reentry-pf's, run on 11 seeds
(51 seeds would add about 20 s each). The particle filter step's statistical check fails a correct step
with probability 5e-7 per seed (its module's docstring); the seeds here are fixed, so a failure would
repeat on every run.
"""

from __future__ import annotations

import pytest

from autograder import cells
from autograder.catalogues.mistakes import catalogue
from lab_code import CASE_SEEDS, define, failure_on_seed, hidden_tests
from over_labs import LABS

MISTAKE_SEEDS = {"nonlinear-filters": CASE_SEEDS[:11], "reentry-pf": CASE_SEEDS[:11]}
"""Fewer seeds for the mistakes of a lab whose checks are slow (the default: all of ``CASE_SEEDS``)."""


def _answers(lab) -> dict[str, str]:
    return cells.model_answers(cells.read(lab.source_notebook))


BLANKS = [(lab, blank) for lab in LABS for blank in lab.blanks()]


@pytest.mark.parametrize("lab, blank", BLANKS, ids=[f"{lab.id}-{blank}" for lab, blank in BLANKS])
def test_the_reference_and_the_model_answer_pass_on_every_seed(lab, blank):
    check = getattr(hidden_tests(lab), f"check_{blank}").__wrapped__
    answers = {"the reference": getattr(lab.reference(), blank), "the model answer": define(lab, _answers(lab)[blank], blank)}
    failures = [f"{who} on seed {seed}: {type(error).__name__}: {error}"
                for who, function in answers.items() for seed in CASE_SEEDS
                if (error := failure_on_seed(check, function, seed)) is not None]
    assert not failures, "\n".join(failures)


MISTAKES = [(lab, mistake) for lab in LABS for mistake in catalogue(lab)]


@pytest.mark.parametrize("lab, mistake", MISTAKES, ids=[m.student_id(lab) for lab, m in MISTAKES])
def test_each_mistake_fails_its_blanks_check_on_every_seed(lab, mistake):
    check = getattr(hidden_tests(lab), f"check_{mistake.blank}").__wrapped__
    wrong = define(lab, mistake.apply(_answers(lab)[mistake.blank]), mistake.blank)
    problems = []
    for seed in MISTAKE_SEEDS.get(lab.id, CASE_SEEDS):
        error = failure_on_seed(check, wrong, seed)
        if error is None:
            problems.append(f"seed {seed}: passes")
        elif type(error) is not mistake.raises:
            problems.append(f"seed {seed}: {type(error).__name__} ({error}), not {mistake.raises.__name__}")
    assert not problems, f"{mistake.student_id(lab)} on the hidden test of {mistake.blank}:\n" + "\n".join(problems)

"""Right both ways: the bank of correct alternatives (``solutions/<module>/alternatives.py``) keeps full marks.

Every blank of every lab has at least one correct alternative; each passes its blank's visible checks
(the solved notebook's cells run in this process, as tests/test_check_messages.py runs them, with the
alternative defined in place of the model answer before the blank's check cell) and its blank's hidden
check on the default submission seed and 50 others. An alternative that fails is a defect of the check.

Cost on one worker of the shared 2-core machine, whose load average other engineers kept at 6 to 9 (fair-a,
two runs): train-kf 10-20 s, castaway-bob 21-41 s, nonlinear-filters 91-183 s, most of it its three
bootstrap_pf_step alternatives (the 100,000-particle noise test on 51 seeds) and its three moment_error
alternatives (loops over the monomials of CUT8 at degree 8).
"""

from __future__ import annotations

from collections import Counter

import pytest

from autograder import cells
from autograder.authoring.visible_checks import visible_verdicts
from autograder.catalogues.alternatives import Alternative, catalogue
from autograder.labs import Lab
from lab_code import CASE_SEEDS, define, failure_on_seed, hidden_tests
from over_labs import LABS, over_labs


def _bank(lab: Lab) -> tuple[Alternative, ...]:
    """The lab's alternatives, or none for a lab without a bank (whose per-lab tests below then fail)."""
    try:
        return catalogue(lab)
    except ModuleNotFoundError as error:
        if error.name != f"solutions.{lab.module}.alternatives":
            raise
        return ()


@over_labs
def test_every_blank_has_a_correct_alternative(lab: Lab):
    alternatives = catalogue(lab)  # a lab without solutions/<module>/alternatives.py fails here
    blanks = lab.blanks()
    counts = Counter(a.blank for a in alternatives)
    assert set(counts) <= set(blanks), f"alternatives for unknown blanks: {set(counts) - set(blanks)}"
    assert all(counts[b] >= 1 for b in blanks), f"blanks without an alternative: {[b for b in blanks if not counts[b]]}"
    ids = [a.student_id(lab) for a in alternatives]
    assert len(ids) == len(set(ids)), "alternative slugs are unique within a blank"
    answers = cells.model_answers(cells.read(lab.source_notebook))
    for alternative in alternatives:
        assert alternative.code.strip() != answers[alternative.blank].strip(), f"{alternative.slug} is the model answer"
        assert callable(define(lab, alternative.code, alternative.blank)), f"{alternative.slug} defines no {alternative.blank}"


ALTERNATIVES = [(lab, alternative) for lab in LABS for alternative in _bank(lab)]


@pytest.mark.parametrize("lab, alternative", ALTERNATIVES, ids=[a.student_id(lab) for lab, a in ALTERNATIVES])
def test_each_alternative_passes_its_blanks_hidden_check_on_every_seed(lab: Lab, alternative: Alternative):
    check = getattr(hidden_tests(lab), f"check_{alternative.blank}")
    function = define(lab, alternative.code, alternative.blank)
    failures = [f"seed {seed}: {type(error).__name__}: {error}" for seed in CASE_SEEDS
                if (error := failure_on_seed(check, function, seed)) is not None]
    assert not failures, f"{alternative.student_id(lab)} fails the hidden test of {alternative.blank}:\n" + "\n".join(failures)


@over_labs
def test_each_alternative_passes_its_blanks_visible_checks(lab: Lab):
    """Each alternative in place of the model answer, with its blank's visible checks, in the solved
    notebook run in this process (autograder/authoring/visible_checks.py)."""
    alternatives = catalogue(lab)
    verdicts = visible_verdicts(lab, [(a.student_id(lab), a.blank, a.code) for a in alternatives])
    assert len(verdicts) == len(alternatives), "every alternative's blank has a visible check cell"
    failures = [f"{key}: {type(error).__name__}: {error}" for key, error in verdicts.items() if error is not None]
    assert not failures, "\n".join(failures)

"""The hidden tests pass the reference and fail every catalogued mistake, without nbgrader.

This is the fast twin of the grading round trip (test_round_trip.py): it runs each blank's
``check_<blank>`` directly on the reference function and on the function each mistake defines.
"""

import importlib
from collections import Counter

import pytest

from autograder import cells
from autograder.mistakes import catalogue
from over_labs import LABS, over_labs


def _hidden(lab):
    return importlib.import_module(f"autograder.hidden_tests.{lab.module}")


def _define(lab, code: str, name: str):
    """The function ``name`` that ``code`` defines, in the reference module's namespace."""
    namespace = dict(vars(lab.solutions()))
    exec(compile(code, f"<answer {name}>", "exec"), namespace)
    return namespace[name]


@over_labs
def test_every_check_passes_the_reference(lab):
    reference = lab.solutions()
    for name in cells.blank_names(cells.read(lab.source_notebook)):
        getattr(_hidden(lab), f"check_{name}")(getattr(reference, name))


@over_labs
def test_every_check_passes_the_model_answer_as_the_notebook_defines_it(lab):
    answers = cells.model_answers(cells.read(lab.source_notebook))
    for name in cells.blank_names(cells.read(lab.source_notebook)):
        getattr(_hidden(lab), f"check_{name}")(_define(lab, answers[name], name))


@over_labs
def test_each_blank_has_at_least_two_catalogued_mistakes(lab):
    counts = Counter(m.blank for m in catalogue(lab))
    blanks = cells.blank_names(cells.read(lab.source_notebook))
    assert set(counts) <= set(blanks), f"mistakes for unknown blanks: {set(counts) - set(blanks)}"
    assert all(counts[b] >= 2 for b in blanks), {b: counts[b] for b in blanks}
    ids = [m.student_id(lab) for m in catalogue(lab)]
    assert len(ids) == len(set(ids)), "mistake slugs are unique within a blank"


MISTAKES = [(lab, m) for lab in LABS for m in catalogue(lab)]


@pytest.mark.parametrize("lab, mistake", MISTAKES, ids=[m.student_id(lab) for lab, m in MISTAKES])
def test_each_mistake_fails_its_blanks_hidden_tests(lab, mistake):
    answer = cells.model_answers(cells.read(lab.source_notebook))[mistake.blank]
    wrong = _define(lab, mistake.apply(answer), mistake.blank)
    with pytest.raises(Exception):
        getattr(_hidden(lab), f"check_{mistake.blank}")(wrong)

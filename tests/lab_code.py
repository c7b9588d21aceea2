"""A lab's hidden tests, a student's answer defined as its answer cell would define it, and a hidden test run
with the cases of one submission seed: shared by tests/test_hidden_tests.py, tests/test_diagnosis.py,
tests/test_case_seeds.py and tests/test_alternatives.py."""

from __future__ import annotations

from collections.abc import Callable
from types import ModuleType

from autograder.hidden_tests import cases
from autograder.labs import Lab


def hidden_tests(lab: Lab) -> ModuleType:
    """``solutions.<module>.hidden_tests``."""
    return lab.hidden_module("hidden_tests")


def answer_file(name: str) -> str:
    """The file name a traceback gives for the answer that defines ``name``."""
    return f"<answer {name}>"


def define(lab: Lab, code: str, name: str) -> Callable:
    """The function ``name`` that ``code`` defines, in the reference module's namespace, as a
    student's answer cell would define it."""
    namespace = dict(vars(lab.reference()))
    exec(compile(code, answer_file(name), "exec"), namespace)
    return namespace[name]


CASE_SEEDS = (cases.DEFAULT_SEED, *range(1, 51))
"""The submission seeds a hidden check must be right on in the tests: the default seed and 50 others."""


def failure_on_seed(check: Callable, function: Callable, seed: int) -> BaseException | None:
    """What the hidden test ``check`` raises on ``function`` with the cases of submission seed ``seed``
    (None: it passes)."""
    with cases.seeded(seed):
        try:
            check(function)
        except Exception as error:  # noqa: BLE001 (which exception, on which seed, is what the tests report)
            return error
    return None

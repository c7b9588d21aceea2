"""A lab's hidden tests, and a student's answer defined as its answer cell would define it: shared by
tests/test_hidden_tests.py and tests/test_diagnosis.py."""

from __future__ import annotations

from collections.abc import Callable
from types import ModuleType

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

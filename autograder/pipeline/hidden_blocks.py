"""The hidden block of a graded test cell: where it is, and which check it names.

A graded test cell of blank ``f`` ends with a hidden block that nbgrader strips from the release::

    ### BEGIN HIDDEN TESTS
    from solutions.<module>.hidden_tests import check_f
    check_f(f)
    ### END HIDDEN TESTS

Run by hand or by nbval on a source notebook, where the reference is legitimately present, the
block runs as written. In grading, the kernel never runs it: the grader reads from it which check
to run in its own process (autograder/pipeline/check_runner.py), and refuses any other form.
"""

from __future__ import annotations

import ast
import functools
import importlib
import re
from dataclasses import dataclass
from typing import Callable, Iterable

from nbformat import NotebookNode

from autograder import cells

BEGIN, END = "### BEGIN HIDDEN TESTS", "### END HIDDEN TESTS"
HIDDEN_MODULE = re.compile(r"solutions\.[a-z0-9_]+\.hidden_tests")
"""Where a hidden block imports its check from: ``solutions.<module>.hidden_tests``."""


class HiddenTestFormError(ValueError):
    """A hidden block that is not of the one form the grader runs."""


class ReferenceUnavailable(RuntimeError):
    """The grader's process cannot import a hidden test or the reference it compares with."""


@dataclass(frozen=True)
class HiddenTest:
    """The hidden test of one cell: ``check`` from ``module``, called on the student's ``blank``."""

    module: str
    check: str
    blank: str

    def load(self) -> Callable:
        """The check function, imported in this process; ReferenceUnavailable if it cannot be."""
        try:
            return getattr(importlib.import_module(self.module), self.check)
        except (ImportError, AttributeError) as error:
            raise ReferenceUnavailable(
                f"The grader cannot import {self.module}.{self.check} ({type(error).__name__}: {error}). Every "
                "hidden test would fail, so nothing was graded. Run the grader from the course root (plain "
                "nbgrader reads nbgrader_config.py there, which puts the root on the grader's path)."
            ) from None


def prepare(tests: Iterable[HiddenTest]) -> None:
    """Call, once per process, the ``prepare()`` of each hidden-test module that has one: work that
    does not depend on the student (a reference ensemble) is done before the checks are forked
    (autograder/pipeline/confined_check.py), so that every check's child inherits it instead of
    redoing it for every submission."""
    for module in sorted({test.module for test in tests}):
        _prepare(module)


@functools.cache
def _prepare(module: str) -> None:
    hook = getattr(importlib.import_module(module), "prepare", None)
    if hook is not None:
        hook()


def split(source: str) -> tuple[str, str | None]:
    """A test cell's source: (the visible part, the hidden block's code or None)."""
    if BEGIN not in source:
        return source, None
    before, _, rest = source.partition(BEGIN)
    hidden, _, after = rest.partition(END)
    return (before + after).rstrip() + "\n" if (before + after).strip() else "", hidden


def hidden_test(code: str) -> HiddenTest:
    """The hidden test that a hidden block's code states; HiddenTestFormError unless it is exactly
    ``from solutions.<module>.hidden_tests import check_<f>`` then ``check_<f>(<f>)``.

    The module and the blank are read from where the form has them, then the block must be, statement
    for statement, the form written out with them (comments and layout aside)."""
    try:
        body = ast.parse(code).body
    except SyntaxError as error:
        raise HiddenTestFormError(f"the hidden block does not parse: {error}") from None
    try:
        module, blank = body[0].module, body[1].value.args[0].id
    except (IndexError, AttributeError):
        module = blank = None
    if isinstance(module, str) and HIDDEN_MODULE.fullmatch(module) and isinstance(blank, str):
        form = ast.parse(f"from {module} import check_{blank}\ncheck_{blank}({blank})").body
        if ast.dump(ast.Module(body, [])) == ast.dump(ast.Module(form, [])):
            return HiddenTest(module, f"check_{blank}", blank)
    raise HiddenTestFormError("the hidden block is not `from solutions.<module>.hidden_tests import check_f` then "
                              f"`check_f(f)`:\n{code}")


def hidden_tests(nb: NotebookNode) -> dict[int, HiddenTest]:
    """Cell index -> hidden test, for every autograded test cell with a hidden block. Only those: a
    cell of the student's own that holds hidden-block markers is just code to the grader (the
    sanitize step restores every test cell from the gradebook)."""
    found = {}
    for index, cell in enumerate(nb.cells):
        if cells.is_autograded_test(cell):
            _, code = split(cell.source)
            if code is not None:
                found[index] = hidden_test(code)
    return found

"""Helpers for the hidden tests, which run only in the grading kernel.

Partial credit is isolated: a blank's hidden tests call the student's function with every other
blank it uses bound to the reference, so that one mistake costs one blank's points.
"""

from __future__ import annotations

import types
from typing import Callable, Iterable


def isolate(func: Callable, reference: types.ModuleType, blanks: Iterable[str]) -> Callable:
    """A copy of ``func`` that sees the reference's version of every other blank in ``blanks``.

    The notebook's namespace is left alone: only the copy sees the reference functions.
    """
    if not isinstance(func, types.FunctionType):
        raise AssertionError(f"{func!r} should be a function defined with `def`.")
    others = {name: getattr(reference, name) for name in blanks if name != func.__name__}
    namespace = {**func.__globals__, **others}
    copy = types.FunctionType(func.__code__, namespace, func.__name__, func.__defaults__, func.__closure__)
    copy.__kwdefaults__ = func.__kwdefaults__
    return copy

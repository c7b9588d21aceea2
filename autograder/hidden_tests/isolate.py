"""Helpers for the hidden tests, which run in the grader's process (autograder/pipeline/check_runner.py), or
in the kernel of a source notebook run by hand, where the reference is present.

Partial credit is isolated: a blank's hidden tests call the student's function with the other
blanks that the reference's own version of it calls bound to the reference, so that one mistake
costs one blank's points. Only those: a blank whose answer called another blank that its reference
does not call (a covariance-form gain that returns the information-form gain) would otherwise be
handed the reference's answer for its own work.

Warnings are failures with a message. nbgrader gives 0 to a test cell that writes to stderr, but
Python shows a warning only the first time a line triggers it, so the score would depend on which
cell ran first; here it is the same every time, and the student is told why.
"""

from __future__ import annotations

import abc
import contextlib
import functools
import types
import warnings
from typing import Callable, Iterable, Iterator

from autograder.kernel import wire
from course.checks import changed_arguments_failure, global_random_failure


def _named_blanks(reference: types.ModuleType, name: str, blanks: frozenset[str]) -> set[str]:
    """The blanks whose names the reference's ``name`` uses, in its code or in the code of functions
    defined inside it."""
    names: set[str] = set()
    code = getattr(getattr(reference, name, None), "__code__", None)
    codes = [code] if code is not None else []
    while codes:
        code = codes.pop()
        names.update(code.co_names)
        codes += [const for const in code.co_consts if isinstance(const, types.CodeType)]
    return {blank for blank in blanks if blank in names}


def called_blanks(reference: types.ModuleType, name: str, blanks: Iterable[str]) -> frozenset[str]:
    """The blanks among ``blanks``, other than ``name``, that the reference's ``name`` calls, directly or
    through another blank it calls (run_rank4 calls kalman_step, which calls kalman_gain: a run that
    writes the step out with the gain calls it too); none if it has no such function."""
    blanks = frozenset(blanks)
    found: set[str] = set()
    todo = [name]
    while todo:
        for blank in _named_blanks(reference, todo.pop(), blanks) - found - {name}:
            found.add(blank)
            todo.append(blank)
    return frozenset(found)


_observer: Callable | None = None
"""While a diagnosed check runs (autograder/hidden_tests/diagnosis.py): called as ``observer(function,
args, kwargs)`` in place of each call of an isolated function, so that the diagnosis sees every case
the student's function saw and what it gave, without calling it again."""


@contextlib.contextmanager
def observed(observer: Callable) -> Iterator[None]:
    """Route every call of an isolated function through ``observer`` inside the block."""
    global _observer
    before, _observer = _observer, observer
    try:
        yield
    finally:
        _observer = before


def _observable(function: Callable) -> Callable:
    """``function``, called through the observer when one is set (``observed``)."""
    @functools.wraps(function)
    def call(*args, **kwargs):
        observer = _observer
        return function(*args, **kwargs) if observer is None else observer(function, args, kwargs)

    return call


def isolate(func: Callable, reference: types.ModuleType, blanks: Iterable[str], *, warnings_fail: bool = True) -> Callable:
    """A copy of ``func`` that sees the reference's version of each other blank in ``blanks`` that
    the reference's own version of ``func`` calls (``called_blanks``); other names are its own.

    The notebook's namespace is left alone: only the copy sees the reference functions. With
    ``warnings_fail`` (the default) a warning in the copy fails with a message; a check that turns
    warnings into failures with a more specific hint of its own passes False. Every call of the copy
    can be observed (``observed``), as the diagnosis does.
    """
    return _observable(_isolated(func, reference, blanks, warnings_fail))


class RemoteFunction(abc.ABC):
    """A student's function that runs elsewhere (in the grading kernel: autograder/pipeline/student_function.py),
    which ``isolate`` asks for its isolated copy instead of copying it here."""

    @abc.abstractmethod
    def isolated(self, reference: types.ModuleType, blanks: Iterable[str], warnings_fail: bool) -> Callable:
        """The same function, seeing the reference's version of the other blanks that the reference's own
        version calls (``called_blanks``), and failing on a warning if ``warnings_fail``."""


def with_globals(function: Callable, names: dict[str, Callable]) -> Callable:
    """A copy of ``function`` that sees ``names`` in place of its module's (anything but a plain
    function is returned as it is)."""
    if not isinstance(function, types.FunctionType):
        return function
    copied = types.FunctionType(function.__code__, {**function.__globals__, **names}, function.__name__,
                                function.__defaults__, function.__closure__)
    copied.__kwdefaults__ = function.__kwdefaults__
    return copied


WARNING_CAUSES = (
    ("No artists with labels found to put in legend",
     "Nothing labelled was drawn on the Axes you were given: draw with ax.plot and ax.fill_between on that ax. "
     "plt.plot and plt.fill_between draw on pyplot's current Axes, which is another one when you are graded."),
)
"""(a warning message's beginning, its likely cause in a graded function): for warnings whose cause is not numeric."""


def warning_failure(name: str, category: str, message: str) -> str:
    """Why a graded function that warned fails: the warning, then its likely cause."""
    cause = next((why for start, why in WARNING_CAUSES if message.startswith(start)), None)
    if cause is None and category == "RuntimeWarning":
        cause = ("Find the computation that triggers it (a log or square root of a negative number, a division by "
                 "zero, an overflow) and fix it.")
    return (f"{name} gave the warning {category}: {message.rstrip('.')}. A graded function must run without warnings. "
            f"{cause or 'Find the call that gives it and change it.'}")


def fail_if_warned(name: str, caught: list[tuple[str, str]]) -> None:
    """Raise the AssertionError of a graded function ``name`` that warned (``warning_failure``) for the first of
    ``caught``, the (category's name, message) of each warning its call gave; return None when there is none."""
    if caught:
        raise AssertionError(warning_failure(name, *caught[0]))


class CallRuleBroken(AssertionError):
    """A call that broke one of the rules every lab states (no writes into arguments, draws only from rng): its
    numbers may be right, so no sentence on the cases where they are right or wrong is added to it."""


def _checked(function: Callable, name: str) -> Callable:
    """``function``, failing as graded functions fail when it changes an array argument in place, or draws
    from NumPy's global generator when it is given one: what the kernel reports of each call in grading
    (autograder/kernel/wire.py, ``Peer.answer``), found here with the same functions."""
    @functools.wraps(function)
    def call(*args, **kwargs):
        given = wire.arrays_given(args, kwargs)
        drawn = wire.global_random_state()
        result = function(*args, **kwargs)
        changed = wire.changed_names(function, given, args, kwargs)
        if changed:
            raise CallRuleBroken(changed_arguments_failure(name, changed))
        if wire.uses_a_generator(args, kwargs) and wire.global_random_state() != drawn:
            raise CallRuleBroken(global_random_failure(name))
        return result

    return call


def _isolated(func: Callable, reference: types.ModuleType, blanks: Iterable[str], warnings_fail: bool) -> Callable:
    """``isolate``'s copy of ``func``, not yet observable."""
    if isinstance(func, RemoteFunction):  # grading: the function is in the kernel
        return func.isolated(reference, blanks, warnings_fail)
    if not isinstance(func, types.FunctionType):
        raise AssertionError(f"{func!r} should be a function defined with `def`.")
    others = {name: getattr(reference, name) for name in called_blanks(reference, func.__name__, blanks)}
    copy = _checked(with_globals(func, others), func.__name__)
    if not warnings_fail:
        return copy

    @functools.wraps(func)
    def without_warnings(*args, **kwargs):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            result = copy(*args, **kwargs)
        fail_if_warned(func.__name__, [(w.category.__name__, str(w.message)) for w in caught])
        return result

    return without_warnings

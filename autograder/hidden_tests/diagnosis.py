"""Hidden-test messages that name a catalogued mistake.

"The largest difference from the reference is 0.381" tells a student nothing. Every hidden test
``check_<blank>`` is decorated with :func:`diagnosed`: when it fails, the decorator asks whether
the student's function behaves, on that test's own hidden cases, exactly like one of the blank's
catalogued mistakes (``solutions/<module>/mistakes.py``), and if exactly one matches, it adds
that mistake's ``hint`` to the failure's message. The student reads the hint in the feedback; it
describes the mistake in words and shows none of the reference's numbers or code.

How a match is found, only after a failure and only for that blank's mistakes:

1. the cases: while the check runs, every call it makes of the student's (isolated) function is
   recorded (``isolate.observed``): a copy of its arguments taken before the call, and what the
   student's function gave. The diagnosis never calls the student's function again, so it shows
   nothing about a case the student's function was not already given in that test (a kernel that
   prints what it is called with learns nothing more from a diagnosis);
2. each mistake's function is the model answer (the reference's source in ``solutions/``, which a
   test keeps identical to the notebook's answer cell) with the mistake's edit, executed in the
   reference module's namespace, so that it sees the reference for every other blank, as the
   student's function does through ``isolate``;
3. the reference and the candidate mistakes are called on copies of every recorded input. A mistake
   matches if its results equal the student's on every call, within ``RTOL``/``ATOL``: the
   returned values, anything the call wrote into a dict argument (``info``), the state a random
   generator argument is left in, and the type of the exception where a call raises.

A diagnosis is given only if the student's results differ from the reference's somewhere (a
failure for another reason, a warning or a wrong type, is left alone) and exactly one mistake
matches; several matches give no diagnosis rather than a guess. Stochastic blanks are diagnosed
the same way: the recorded generator states make the student's and the mistakes' draws the same
whenever they draw in the reference's order, and a student who draws otherwise is simply not
diagnosed. A plot blank is compared by what its Axes show (the data of its lines and filled
regions, and whether it has a legend and a title), not by colours or labels. Results that cannot be compared
give no diagnosis.

The diagnosis never changes a score: it edits the message of the exception the test raised, names
the mistake's slug in the exception's ``MISTAKE_ATTRIBUTE`` (which the grader records as data beside
the verdict, autograder/pipeline/verdicts.py: the class report counts it), and re-raises it. It gives up silently when it runs out of time (``BUDGET_S``, and ``CELL_SHARE`` of the
grading cell's time limit for the test and the diagnosis together), or on any error of its own. A
diagnosis that runs out of time is checked only between calls: one call of the reference or of a
mistake can overrun it. The cost falls on failing submissions (the reference's and the mistakes'
calls on the recorded cases), apart from a copy of each case's arguments while the check runs.
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import functools
import inspect
import io
import os
import sys
import time
import types
import warnings
from typing import Any, Callable

import numpy as np

from autograder.hidden_tests import isolate
from autograder.hidden_tests import case_kinds
from autograder.hidden_tests.case_kinds import add_to_message
from autograder.labs import lab_of
from autograder.catalogues.mistakes import Mistake, catalogue

RTOL = 1e-6
"""Relative tolerance of a match: far tighter than any two different mistakes differ, loose enough
for a student who writes the same mistake with other, equivalent, operations."""
ATOL = 1e-9
"""Absolute tolerance, relative to the largest entry of the compared array (and 1e-12 at least)."""
BUDGET_S = 12.0
"""Seconds the diagnosis may take at most before it gives up."""
CELL_SHARE = 0.6
"""The hidden test and its diagnosis together stay within this share of the grading cell's time limit
(``GRADING_CELL_TIMEOUT``, 30 s by default, see nbgrader_config.py), so that a diagnosis never turns
a failure with a message into a stopped cell."""

LEAD = "Diagnosis: on every hidden case, your {blank} gives the same results as a common mistake."
"""The sentence before the mistake's hint in the message."""
MISTAKE_ATTRIBUTE = "kit_diagnosed_mistake"
"""The attribute of a failed check's exception that holds the diagnosed mistake's slug."""


class _OutOfTime(Exception):
    """The diagnosis used up its budget."""


class _Unsupported(Exception):
    """A result the diagnosis cannot compare."""


def diagnosed(check: Callable) -> Callable:
    """Decorate the hidden test ``check_<blank>`` of ``solutions.<module>.hidden_tests`` so that its
    failures name the catalogued mistake the student's function behaves like, if exactly one does,
    and, where its cases are labelled (autograder/hidden_tests/case_kinds.py), say on which kinds of
    case the function is right and on which wrong."""
    blank = _blank(check)

    @functools.wraps(check)
    def diagnosing_check(func: Callable, *args, **kwargs):
        start = time.monotonic()
        calls: list[tuple[tuple, Any]] = []
        single: set[str] = set()
        try:
            with isolate.observed(_recorder(calls, single)), case_kinds.labelled(blank):
                return check(func, *args, **kwargs)
        except Exception as error:
            precision = _precision_mistake(check)
            if (single and isinstance(error, AssertionError) and not isinstance(error, isolate.CallRuleBroken)
                    and "single precision" not in str(error)):
                # a fairness review of issue 30: a float32 answer was sent to a formula or to the kinds of case;
                # the catalogued float32 mistake is named without matching its numbers, whose rounding differs
                # from the student's with the order of the operations (it was named on some seeds only)
                if precision is not None:
                    add_to_message(error, f"{LEAD.format(blank=blank)} {precision.hint}")
                    setattr(error, MISTAKE_ATTRIBUTE, precision.slug)
                    raise
                add_to_message(error, f"Your {blank} returned {min(single)} (single precision, about 7 significant "
                                      "digits): compute in float64, NumPy's default, and do not convert to float32.")
            mistake = _diagnosis(check, calls, _budget(time.monotonic() - start))
            if mistake is not None:
                add_to_message(error, f"{LEAD.format(blank=blank)} {mistake.hint}")
                setattr(error, MISTAKE_ATTRIBUTE, mistake.slug)
            raise

    diagnosing_check.diagnosed_blank = blank
    return diagnosing_check


def diagnosed_mistake(error: BaseException) -> str | None:
    """The slug of the catalogued mistake that ``diagnosed`` found behind the failure ``error``, or None."""
    slug = getattr(error, MISTAKE_ATTRIBUTE, None)
    return slug if isinstance(slug, str) else None


def _blank(check: Callable) -> str:
    """The blank that the hidden test ``check_<blank>`` grades."""
    return check.__name__.removeprefix("check_")


def diagnose(func: Callable, check: Callable, args: tuple = (), kwargs: dict | None = None,
             budget_s: float = BUDGET_S) -> Mistake | None:
    """The one catalogued mistake of the blank that ``check`` grades (``check_<blank>``, the
    undecorated hidden test in ``solutions.<module>.hidden_tests``, called with ``args`` and
    ``kwargs``) whose results equal ``func``'s on every case that ``check`` gave ``func``, or None."""
    calls: list[tuple[tuple, Any]] = []
    with contextlib.suppress(Exception), isolate.observed(_recorder(calls)):
        check(func, *args, **(kwargs or {}))
    return _diagnosis(check, calls, budget_s)


def _single_precision(result) -> set[str]:
    """The floating-point dtypes less precise than float64 in a result (arrays, NumPy scalars, in tuples and lists)."""
    if isinstance(result, (tuple, list)):
        return set().union(*(_single_precision(item) for item in result)) if result else set()
    dtype = getattr(result, "dtype", None)
    return {str(dtype)} if isinstance(dtype, np.dtype) and dtype.kind == "f" and dtype.itemsize < 8 else set()


def _recorder(calls: list, single: set[str] | None = None) -> Callable:
    """An observer (isolate.observed) that makes each call and appends (a copy of its arguments
    taken before the call, its outcome) to ``calls``; an outcome it cannot compare is None."""
    def observe(function: Callable, args: tuple, kwargs: dict):
        try:
            snapshot = _copy((args, kwargs))
        except Exception:  # noqa: BLE001 (arguments it cannot copy: this case is not recorded)
            snapshot = None
        try:
            result = function(*args, **kwargs)
        except Exception as error:
            if snapshot is not None:
                calls.append((snapshot, ("raises", type(error))))
            raise
        if single is not None:
            single.update(_single_precision(result))
        if snapshot is not None:
            try:
                calls.append((snapshot, _leaves((result, _written(args, kwargs)))))
            except Exception:  # noqa: BLE001 (a result it cannot compare)
                calls.append((snapshot, None))
        return result

    return observe


def _precision_mistake(check: Callable) -> Mistake | None:
    """The catalogued mistake of the check's blank that computes in single precision, if it has one."""
    return next((m for m in catalogue(lab_of(check.__module__)) if m.blank == _blank(check)
                 and "single precision" in m.hint), None)


def _diagnosis(check: Callable, calls: list, budget_s: float) -> Mistake | None:
    """The diagnosis of a failed check from the calls it made (``_recorder``), or None."""
    deadline = time.monotonic() + budget_s
    try:
        with _quiet():
            return _diagnose(check, calls, deadline)
    except Exception:  # noqa: BLE001 (out of time, an unsupported result, a crash: no diagnosis, same score)
        return None


def _budget(elapsed_s: float) -> float:
    """Seconds left for a diagnosis after a hidden test that took ``elapsed_s``."""
    cell_limit = float(os.environ.get("GRADING_CELL_TIMEOUT", "30"))
    return min(BUDGET_S, CELL_SHARE * cell_limit - elapsed_s)


def mistake_function(reference: types.ModuleType, mistake: Mistake) -> Callable:
    """The model answer of ``mistake.blank`` (its source in ``reference``) with the mistake made,
    defined in a copy of the reference module's namespace."""
    source = inspect.getsource(getattr(reference, mistake.blank))
    namespace = dict(vars(reference))
    exec(compile(mistake.apply(source), reference.__file__, "exec"), namespace)
    return namespace[mistake.blank]


def _diagnose(check, calls, deadline) -> Mistake | None:
    blank = _blank(check)
    lab = lab_of(check.__module__)
    reference = lab.reference()
    mistakes = [m for m in catalogue(lab) if m.blank == blank]
    if not mistakes or not calls or any(outcome is None for _, outcome in calls):
        return None
    results = [outcome for _, outcome in calls]
    if _matches(getattr(reference, blank), calls, results, deadline):
        return None  # it fails for another reason than its results: a warning, an edited input, ...
    matches = [m for m in mistakes if _matches(mistake_function(reference, m), calls, results, deadline)]
    return matches[0] if len(matches) == 1 else None


def _outcome(function, call_args, deadline):
    """What ``function`` returns on a copy of the recorded arguments (and writes into them), or the
    type of the exception it raises."""
    if time.monotonic() > deadline:
        raise _OutOfTime
    positional, keywords = _copy(call_args)
    try:
        result = function(*positional, **keywords)
    except Exception as error:  # noqa: BLE001 (a crash is an outcome: the mistake may crash the same way)
        return ("raises", type(error))
    return _leaves((result, _written(positional, keywords)))


def _matches(function, calls, results, deadline) -> bool:
    """Whether ``function`` has the student's ``results`` on every recorded call (it stops at the
    first difference)."""
    return all(_same(_outcome(function, call_args, deadline), got) for (call_args, _), got in zip(calls, results))


def _written(positional: tuple, keywords: dict) -> list:
    """The arguments a call may legitimately write into: dicts (``info``), random generators and
    the Axes a plot blank draws on."""
    return [a for a in (*positional, *keywords.values()) if isinstance(a, (dict, np.random.Generator)) or _is_axes(a)]


def _copy(call_args: tuple) -> tuple:
    """A deep copy of recorded arguments, with every Axes among them replaced by a fresh empty one
    (a plot blank's test hands it an empty Axes; Axes do not copy)."""
    memo: dict = {}
    for value in (*call_args[0], *call_args[1].values()):
        if _is_axes(value):
            if value.has_data() or value.get_legend() is not None:
                raise _Unsupported("an Axes that already holds a plot")
            from matplotlib.figure import Figure
            memo[id(value)] = Figure().subplots()
    return copy.deepcopy(call_args, memo)


def _is_axes(value) -> bool:
    axes = sys.modules.get("matplotlib.axes")
    return axes is not None and isinstance(value, axes.Axes)


def _leaves(value) -> list:
    """A comparable, flat form of a result: arrays of floats and exact values, with the structure
    written into the exact values. Raises _Unsupported for a value it cannot compare."""
    if isinstance(value, (bool, str, type(None), np.bool_)):
        return [("exact", value)]
    if isinstance(value, (int, float, complex, np.number, np.ndarray)):
        array = np.asarray(value)
        if array.dtype.kind not in "biufc":
            raise _Unsupported(array.dtype)
        return [("array", array.shape, array.astype(complex if array.dtype.kind == "c" else float))]
    if isinstance(value, np.random.Generator):
        return [("exact", repr(value.bit_generator.state))]
    if isinstance(value, (tuple, list)):
        return [("sequence", len(value))] + [leaf for item in value for leaf in _leaves(item)]
    if isinstance(value, dict):
        keys = sorted(value, key=repr)
        return [("dict", tuple(map(repr, keys)))] + [leaf for key in keys for leaf in _leaves(value[key])]
    if _is_axes(value):
        # what a plot shows, not how it is styled: a student's colours and labels are their own
        lines = [line.get_xydata() for line in value.get_lines()]
        regions = [np.concatenate([path.vertices for path in c.get_paths()] or [np.empty((0, 2))])
                   for c in value.collections]
        return [("axes", len(lines), len(regions), value.get_legend() is not None, any(value.get_title(loc).strip() for loc in ("center", "left", "right")))] + [
            leaf for data in lines + regions for leaf in _leaves(np.asarray(data, dtype=float))]
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = [field.name for field in dataclasses.fields(value)]
        return [("object", type(value).__qualname__, tuple(fields))] + [
            leaf for name in fields for leaf in _leaves(getattr(value, name))]
    raise _Unsupported(type(value))


def _same(first, second) -> bool:
    """Whether two outcomes (leaves, or ("raises", type)) agree within the tolerances."""
    if isinstance(first, tuple) or isinstance(second, tuple):
        return first == second
    if len(first) != len(second):
        return False
    for a, b in zip(first, second):
        if a[0] != "array" or b[0] != "array":
            if a != b:
                return False
            continue
        if a[1] != b[1]:  # shapes
            return False
        finite = np.abs(b[2][np.isfinite(b[2])])
        atol = max(1e-12, ATOL * float(finite.max())) if finite.size else 1e-12
        if not np.allclose(a[2], b[2], rtol=RTOL, atol=atol, equal_nan=True):
            return False
    return True


@contextlib.contextmanager
def _quiet():
    """No warnings, no floating-point complaints and no printed output while the diagnosis runs:
    a graded cell that writes to stderr scores 0, and the student saw their output already."""
    with warnings.catch_warnings(), np.errstate(all="ignore"), contextlib.redirect_stdout(io.StringIO()), \
            contextlib.redirect_stderr(io.StringIO()):
        warnings.simplefilter("ignore")
        yield

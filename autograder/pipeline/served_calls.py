"""Which calls of a served blank the grader answers with the reference.

While the hidden test of blank ``f`` runs, the student's ``f`` calls stand-ins for the earlier blanks
that the reference's ``f`` calls (``g``), and the grader answers them with the reference's ``g``, so
that a mistake in ``g`` costs only ``g``'s points. Answering *any* call would make the served ``g`` an
oracle: a kernel could ask it about inputs of its own choosing, as many as it likes, and print the
answers. So, for each call of the student's ``f``, the grader first runs the reference's ``f`` on a
copy of the same arguments with every served blank recorded, inside the other served blanks too
(``ReferenceUse.of``), and answers a call of a served blank:

- when its arguments are one of the reference's calls (by parameter name, whether passed by position
  or by keyword, defaults filled in; numbers within a relative 1e-6, a random generator in the same
  state; a dict, which the call writes into, whatever it held), each as many times as the reference
  made it, among its next WINDOW calls not answered yet;
- otherwise, when they have the form of one of the reference's calls (the same parameters, types and
  kinds of number, arrays of any shape: a correct ``f`` that integrates with other tolerances or a
  vectorised solver, or calls the quantile function once per order, asks about other points of the
  same kind), while the numbers such calls have asked about stay within twice those the reference's
  calls held, plus WINDOW times its largest call's.

Every other call (another form, or past that budget) is answered by the student's own ``g`` in the
kernel (the stand-in is told ``side.NOT_SERVED``). What a served blank answers says nothing about the
next submission's hidden cases, which its own seed draws (tests/test_harvest.py).
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import inspect
from collections.abc import Callable

import numpy as np

from autograder.hidden_tests.isolate import with_globals

WINDOW = 16
"""A call is looked for among the next WINDOW calls of the reference's that are not answered yet: an
honest f makes them in the reference's order, and a search of all of them made a student whose ODE
solver called the served dynamics at other points (hundreds of calls, none of them the reference's)
wait for a scan of hundreds for each call, past the cell's time limit."""
RTOL = 1e-6
"""Relative tolerance of a match: a correct ``f`` computes its calls' arguments to rounding."""


class NotServed(Exception):
    """A call of a served blank that the reference's ``f`` does not make: its name (side.NOT_SERVED)
    tells the kernel's stand-in to call the student's own blank instead."""


def _matches(got, want) -> bool:
    """Whether two argument structures agree (see the module doc)."""
    if callable(want) and not isinstance(want, type):
        return callable(got)
    if isinstance(want, np.random.Generator):
        return isinstance(got, np.random.Generator) and got.bit_generator.state == want.bit_generator.state
    if isinstance(want, (tuple, list)):
        return isinstance(got, (tuple, list)) and len(got) == len(want) and all(map(_matches, got, want))
    if isinstance(want, dict):
        # a dict argument is where the call writes what it reports (info): what it held before is no input
        return isinstance(got, dict)
    if dataclasses.is_dataclass(want) and not isinstance(want, type):
        return (type(got).__qualname__ == type(want).__qualname__ and dataclasses.is_dataclass(got)
                and all(_matches(getattr(got, f.name, None), getattr(want, f.name)) for f in dataclasses.fields(want)))
    if isinstance(want, (bool, str, type(None), np.bool_)):
        return type(got) is type(want) and got == want
    if isinstance(want, (int, float, complex, np.number, np.ndarray)):
        try:
            a, b = np.asarray(got), np.asarray(want)
        except Exception:  # noqa: BLE001
            return False
        if a.shape != b.shape or a.dtype.kind not in "biufc" or b.dtype.kind not in "biufc":
            return False
        scale = float(np.max(np.abs(b[np.isfinite(b)]), initial=0.0))
        return bool(np.allclose(a, b, rtol=RTOL, atol=RTOL * max(scale, 1e-300), equal_nan=True))
    return False


def _form(value) -> object:
    """A call's (or a value's) form: its structure, types, shapes and kinds of number, not its values."""
    if isinstance(value, dict):  # a call's arguments by name; a dict argument (info) is written into: any content
        return ("arguments", tuple(sorted((str(k), _form(v) if not isinstance(v, dict) else ("dict",))
                                          for k, v in value.items())))
    if isinstance(value, (tuple, list)):
        return (type(value).__name__, tuple(_form(item) for item in value))
    if isinstance(value, np.ndarray):  # of any shape: the blanks take one state or a cloud of them
        return ("array", value.dtype.kind)
    if isinstance(value, (bool, np.bool_)):
        return ("bool",)
    if isinstance(value, (int, float, complex, np.number)):
        return ("number", np.asarray(value).dtype.kind)
    if isinstance(value, np.random.Generator) or callable(value):
        return (type(value).__name__ if not callable(value) else "callable",)
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return (type(value).__qualname__, tuple(_form(getattr(value, f.name)) for f in dataclasses.fields(value)))
    return (type(value).__name__, value if isinstance(value, (str, type(None))) else None)


def _size(value) -> int:
    """How many numbers a call's arguments hold (at least 1)."""
    if isinstance(value, dict):
        return max(1, sum(_size(v) for v in value.values() if not isinstance(v, dict)))
    if isinstance(value, (tuple, list)):
        return max(1, sum(_size(item) for item in value))
    if isinstance(value, np.ndarray):
        return max(1, value.size)
    return 1


def _bound(function: Callable, args: tuple, kwargs: dict) -> dict | None:
    """A call's arguments by parameter name, defaults filled in, so that ``f(x, u)`` and ``f(x, u=u)``
    are the same call; None if they do not fit ``function``'s signature."""
    try:
        bound = inspect.signature(function).bind(*args, **kwargs)
    except (TypeError, ValueError):
        return None
    bound.apply_defaults()
    return dict(bound.arguments)


class ReferenceUse:
    """The calls the reference's ``f`` made of each served blank, on one call's arguments."""

    def __init__(self, calls: dict[str, list[dict]] | None, served: dict[str, Callable] | None = None):
        self.calls = calls
        """blank -> the arguments (by parameter name) of each call not yet answered; None: answer every call."""
        self.served = served or {}
        self.forms = {name: [_form(call) for call in made] for name, made in (calls or {}).items()}
        """blank -> the form of each call the reference made."""
        self.budget = {name: 2 * sum(map(_size, made)) + WINDOW * max(map(_size, made), default=0)
                       for name, made in (calls or {}).items()}
        """blank -> how many numbers it still answers about in calls of a form of the reference's but other
        values: twice as many as the reference's calls held, plus WINDOW of its largest."""

    @classmethod
    def of(cls, reference_function: Callable, served: dict[str, Callable], args: tuple, kwargs: dict) -> "ReferenceUse":
        """Run ``reference_function`` (the reference's ``f``, whose module holds the served blanks) on
        a copy of ``args`` and ``kwargs``, recording each call it makes of a served blank. Arguments
        that cannot be copied give a ReferenceUse that answers every call, as before this guard."""
        try:
            call_args, call_kwargs = copy.deepcopy((args, kwargs))
        except Exception:  # noqa: BLE001 (an argument that cannot be copied: no guard)
            return cls(None)
        calls: dict[str, list[dict]] = {name: [] for name in served}
        recorders: dict[str, Callable] = {}

        def recording(name: str, function: Callable) -> Callable:
            def call(*a, **k):
                with contextlib.suppress(Exception):  # arguments that cannot be copied are not served
                    bound = _bound(function, *copy.deepcopy((a, k)))
                    if bound is not None:
                        calls[name].append(bound)
                return function(*a, **k)
            return call

        # every served blank, and the reference's f, see recording versions of the served blanks (as
        # isolate does), so that a served blank's own calls of another are recorded too: a student's f
        # may make them itself (the update written out with the gain, where the reference calls the step)
        proxies = {name: (lambda *a, _name=name, **k: recorders[_name](*a, **k)) for name in served}
        for name, function in served.items():
            recorders[name] = recording(name, with_globals(function, proxies))
        recorded = with_globals(reference_function, proxies)
        try:
            recorded(*call_args, **call_kwargs)
        except Exception:  # noqa: BLE001 (the reference may reject the case: what it called until then counts)
            pass
        return cls(calls, served)

    def take(self, name: str, args: tuple, kwargs: dict) -> bool:
        """Whether to answer this call of ``name`` with the reference (it is then used up). Calls are
        compared by parameter name, whether each argument was passed by position or by keyword."""
        if self.calls is None:
            return True
        bound = _bound(self.served[name], args, kwargs) if name in self.served else None
        if bound is None:
            return False
        for index, want in enumerate(self.calls.get(name, [])[:WINDOW]):
            if bound.keys() == want.keys() and all(_matches(bound[key], want[key]) for key in want):
                del self.calls[name][index]
                return True
        if _form(bound) in self.forms.get(name, []) and _size(bound) <= self.budget.get(name, 0):
            self.budget[name] -= _size(bound)
            return True
        return False

    def answerer(self, name: str, function: Callable) -> Callable:
        """What the grader calls for the kernel's stand-in of ``name``."""
        def answer(*args, **kwargs):
            if not self.take(name, args, kwargs):
                raise NotServed(f"{name} is called here as the reference's own {name} is not: your own {name} answers")
            return function(*args, **kwargs)

        answer.__name__ = name
        return answer

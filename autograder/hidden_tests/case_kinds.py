"""Hidden cases labelled by what sets them apart, so that a failing hidden test says on which kinds of
case the student's function is right and on which it is wrong.

"The largest difference from the reference is 0.059" does not tell a student where to look. A check
runs its cases inside ``labelled(blank)``, each case inside ``case(...)`` with the properties that
distinguish it, in words: ``case(R="a full R")``, ``case(n="n = 1")``, ``case(weights="zero
weights")``. Inside ``labelled``, a case that fails is recorded and the check goes on with the next,
so the student's function is given every case of the test (no case is replayed: the diagnosis sees
the same calls, autograder/hidden_tests/diagnosis.py). At the end, if any case failed, the first
failure is raised, its message followed by a sentence that narrows the cause, from the properties
alone (never a number of the reference's):

- a property that splits the cases exactly: "Your kupdate is right on every case with a diagonal R
  and wrong on every case with a full R.";
- otherwise the failing cases' properties: "Your kupdate is right on 3 of 5 cases; it is wrong on
  the cases with n = 2 and a full R, and with n = 4 and a diagonal R.";
- nothing more when every case fails.

An error raised in the student's function (not the check's own AssertionError, whose message names
its case) is told on which case it was raised. Outside ``labelled`` (a check that does not use it),
``case`` does nothing and a failure is raised at once, as before. The grader's own interruptions (a kernel that is stuck or gone) always pass through.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import dataclass, field

from autograder.hidden_tests.isolate import CallRuleBroken
from autograder.kernel.wire import PeerGone, PeerTimeout, ProtocolError
from autograder.pipeline.kernel_connection import KernelStopped

MAX_LISTED = 3
"""The most kinds of failing case a sentence lists; beyond, a list says less than the count alone."""
NARROWED = ("is right on every case with", "is right on ")
"""How a narrowing sentence begins after the blank's name (the mutation report counts them)."""
INTERRUPTIONS = (PeerGone, PeerTimeout, ProtocolError, KernelStopped)
"""What a case never records: the grader's own interruptions, which end the test at once."""
WRONG_ONLY_ATTRIBUTE = "kit_wrong_only"
"""The attribute of a failed check's exception that holds, when a property splits the cases exactly,
the cases it was wrong on ("a full R"): the grader records it as data (the class report groups by it)."""


@dataclass
class _Case:
    properties: dict[str, str]
    error: BaseException | None = None


@dataclass
class _Run:
    cases: list[_Case] = field(default_factory=list)


_run: _Run | None = None


@contextlib.contextmanager
def case(**properties: str) -> Iterator[None]:
    """One hidden case, described by the properties that set it apart (each a phrase: "a full R")."""
    run = _run
    if run is None:
        yield
        return
    record = _Case(dict(properties))
    try:
        yield
    except INTERRUPTIONS:
        raise
    except Exception as error:  # noqa: BLE001 (a failing case: recorded, the first is raised at the end)
        if not isinstance(error, AssertionError) and record.properties:
            # the check's own messages name their case; an error raised in the student's function does not
            add_to_message(error, f"It was raised on the case with {_listed(list(record.properties.values()))}.")
        record.error = error
    run.cases.append(record)


@contextlib.contextmanager
def labelled(blank: str) -> Iterator[None]:
    """Run every ``case`` of the block to the end; then raise the first failure, with a sentence on
    where ``blank`` is right and where it is wrong (see the module doc)."""
    global _run
    outer, _run = _run, _Run()
    run = _run
    try:
        yield
    finally:
        _run = outer
    failed = [c for c in run.cases if c.error is not None]
    if not failed:
        return
    error = failed[0].error
    # a broken rule of the call (isolate.CallRuleBroken) says what is wrong; its numbers may be right
    sentence = "" if isinstance(error, CallRuleBroken) else narrowing(blank, run.cases)
    if sentence:
        add_to_message(error, sentence)
    split = None if isinstance(error, CallRuleBroken) else _split(run.cases)
    if split is not None:
        with contextlib.suppress(AttributeError):  # an exception type that takes no attributes keeps its message only
            setattr(error, WRONG_ONLY_ATTRIBUTE, " or ".join(split[1]))
    raise error


def wrong_only(error: BaseException) -> str | None:
    """The kind of case that alone the failure ``error`` was wrong on (``labelled``), or None."""
    found = getattr(error, WRONG_ONLY_ATTRIBUTE, None)
    return found if isinstance(found, str) else None


def _split(cases: list[_Case]) -> tuple[list[str], list[str]] | None:
    """The values of the property that splits the cases exactly, (right on, wrong on), the fewest values
    first; None when no property does (or every case is right, or every case wrong)."""
    wrong = [c for c in cases if c.error is not None]
    right = [c for c in cases if c.error is None]
    if not wrong or not right:
        return None
    splits = []
    for key in dict.fromkeys(k for c in cases for k in c.properties):
        good = {c.properties.get(key) for c in right}
        bad = {c.properties.get(key) for c in wrong}
        if None not in good | bad and not good & bad:
            splits.append((len(bad) + len(good), key, sorted(good), sorted(bad)))
    if not splits:
        return None
    _, _, good, bad = min(splits)
    return good, bad


def narrowing(blank: str, cases: list[_Case]) -> str:
    """The sentence that says on which kinds of case ``blank`` is right and on which wrong ("" if it is
    wrong on every case, or there is nothing to tell the cases apart)."""
    wrong = [c for c in cases if c.error is not None]
    right = [c for c in cases if c.error is None]
    if not wrong or not right:
        return ""
    split = _split(cases)
    if split is not None:
        good, bad = split
        return (f"Your {blank} is right on every case with {' or '.join(good)} and wrong on every case with "
                f"{' or '.join(bad)}.")
    described = [_listed([v for v in c.properties.values()]) for c in wrong]
    unique = list(dict.fromkeys(d for d in described if d))
    if not unique or len(unique) > MAX_LISTED:
        return f"Your {blank} is right on {len(right)} of {len(cases)} cases."
    return (f"Your {blank} is right on {len(right)} of {len(cases)} cases; it is wrong on the cases with "
            f"{_listed(unique, ', and with ')}.")


def _listed(parts: list[str], last: str = " and ") -> str:
    parts = [p for p in parts if p]
    return parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + last + parts[-1] if parts else ""


def add_to_message(error: BaseException, text: str) -> None:
    """Append ``text`` to the message that the traceback shows for ``error``, on the same line: the
    grades table and the notes column show a failure's message as one line."""
    if len(error.args) == 1 and isinstance(error.args[0], str) and type(error).__str__ is BaseException.__str__:
        message = error.args[0].rstrip()
        # NumPy's own messages end without a full stop ("Probabilities contain NaN")
        error.args = (f"{message}{'' if message.endswith(('.', '!', '?', ':')) or not message else '.'} {text}",)
    else:
        error.add_note(text)

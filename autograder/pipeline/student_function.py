"""The student's function as a hidden test's check sees it in the grader: a stand-in whose calls go
over the wire (autograder/kernel/wire.py) to the kernel's server (autograder/kernel/server.py), which
calls the student's function there and sends back what it returned.

Partial credit stays isolated (autograder/hidden_tests/isolate.py, ``isolate``): in the kernel, the
student's ``f`` calls stand-ins for the other blanks that the reference's ``f`` calls, which the grader
answers with the reference, only while this test runs, never for ``f`` itself, only for blanks whose own
hidden test came earlier in the notebook, so that no test can collect the reference's answers for a later
one, nor have a blank it does not need answer for it, and only for the calls that the reference's own
``f`` makes on the same arguments (autograder/pipeline/served_calls.py): any other call is answered by the
student's own blank in the kernel.
"""

from __future__ import annotations

import sys
import types
import warnings
from typing import Callable

from autograder.hidden_tests.isolate import CallRuleBroken, RemoteFunction, called_blanks, fail_if_warned
from autograder.kernel.wire import Peer, warning_class
from autograder.pipeline import served_calls
from course.checks import changed_arguments_failure, global_random_failure


class StudentFunction(RemoteFunction):
    """The student's function in the kernel, as the check sees it: calling it calls theirs there.

    ``earlier`` are the blanks whose hidden tests came before this one: the only ones the grader
    answers for, with the reference, when the student's function calls them (see ``isolated``).
    """

    def __init__(self, peer: Peer, name: str, earlier: frozenset[str], served: dict[str, Callable] | None = None,
                 warnings_fail: bool = False, reference: Callable | None = None):
        self.peer, self.__name__, self.__qualname__ = peer, name, name
        self.earlier, self.served, self.warnings_fail = earlier, served or {}, warnings_fail
        self.reference = reference
        """The reference's version of this blank, whose own calls of the served blanks are the only
        ones the grader answers with the reference (autograder/pipeline/served_calls.py)."""

    def isolated(self, reference: types.ModuleType, blanks, warnings_fail: bool) -> "StudentFunction":
        """The same function, seeing the reference's version of the other blanks that came earlier
        and that the reference's own version calls (autograder/hidden_tests/isolate.py, ``called_blanks``)."""
        served = {name: getattr(reference, name) for name in called_blanks(reference, self.__name__, blanks)
                  if name in self.earlier}
        return StudentFunction(self.peer, self.__name__, self.earlier, served, warnings_fail,
                               getattr(reference, self.__name__, None))

    def __call__(self, *args, **kwargs):
        """The student's function called in the kernel (``Peer.exchange``), the served blanks answered here
        meanwhile; returns what it returned. What it printed is printed here, and what it warned is warned
        here, or fails the call when warnings fail it; a call that changed an array argument in place, or
        drew from NumPy's global generator when given one, fails (CallRuleBroken)."""
        use = (served_calls.ReferenceUse.of(self.reference, self.served, args, kwargs)
               if self.served and self.reference is not None else served_calls.ReferenceUse({}))
        answering = {("served", name): use.answerer(name, function) for name, function in self.served.items()}
        header, buffers = self.peer.exchange("student", args, kwargs, answering, served=sorted(self.served))
        print(str(header.get("stdout", "")), end="")
        print(str(header.get("stderr", "")), end="", file=sys.stderr)
        caught = [(str(c), str(m)) for c, m in header.get("warnings", []) if isinstance(c, str)]
        if header.get("op") == "return" and self.warnings_fail:
            fail_if_warned(self.__name__, caught)
        result = self.peer.apply_answer(header, buffers, args, kwargs)
        if header.get("op") == "return":
            # what the kernel reports that the call did besides returning (autograder/kernel/wire.py, Peer.answer)
            changed = [name[:40] for name in header.get("changed") or [] if isinstance(name, str)]
            if changed:
                raise CallRuleBroken(changed_arguments_failure(self.__name__, changed[:5]))
            if header.get("global_random") is True:
                raise CallRuleBroken(global_random_failure(self.__name__))
        for category, message in caught:
            warnings.warn(message, warning_class(category), stacklevel=2)
        return result

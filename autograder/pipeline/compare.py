"""Hidden tests run in the grader's process, against the student's function in the grading kernel.

A graded test cell of blank ``f`` ends with a hidden block that nbgrader strips from the release::

    ### BEGIN HIDDEN TESTS
    from solutions.<module>.hidden_tests import check_f
    check_f(f)
    ### END HIDDEN TESTS

Run by hand or by nbval on a source notebook, where the reference is legitimately present, the
block runs as written: the check compares in-process (the local mode). In grading, the kernel never
runs it. ``GradingExecute`` runs the cell's visible part in the kernel, then :func:`run_check`
runs ``check_f`` here, in the grader's process (in a forked child capped in memory and time,
autograder/pipeline/confined_check.py), where the reference is, on a :class:`StudentFunction`:
a stand-in whose calls go over a Unix socket to ``autograder/kernel/side.py`` in the kernel, which
calls the student's ``f`` and sends back what it returned. The check's verdict becomes the cell's
outputs: nothing on a pass, the check's error on a failure. Whatever the kernel does, it cannot make
a check pass without returning the reference's values, and it never holds the reference.

Partial credit stays isolated (autograder/hidden_tests/isolate.py, ``isolate``): in the kernel, the student's ``f``
calls stand-ins for the other blanks that the reference's ``f`` calls, which the grader answers with
the reference, only while this test runs, never for ``f`` itself, only for blanks whose own hidden
test came earlier in the notebook, so that no test can collect the reference's answers for a later
one, nor have a blank it does not need answer for it, and only for the calls that the reference's
own ``f`` makes on the same arguments (autograder/pipeline/served_calls.py): any other call is
answered by the student's own blank in the kernel.
"""

from __future__ import annotations

import ast
import contextlib
import functools
import importlib
import io
import os
import re
import shutil
import socket
import sys
import tempfile
import time
import types
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable

from nbformat import NotebookNode
from nbformat.v4 import new_output

from autograder import cells
from autograder.hidden_tests.case_kinds import wrong_only
from autograder.hidden_tests.diagnosis import diagnosed_mistake
from autograder.hidden_tests.isolate import CallRuleBroken, called_blanks, warning_failure
from autograder.kernel import side
from autograder.kernel.side import Peer, PeerGone, PeerTimeout, ProtocolError, Wire, warning_class
from autograder.pipeline import served_calls
from course.checks import changed_arguments_failure, global_random_failure

BEGIN, END = "### BEGIN HIDDEN TESTS", "### END HIDDEN TESTS"
HIDDEN_MODULE = re.compile(r"solutions\.[a-z0-9_]+\.hidden_tests")
"""Where a hidden block imports its check from: ``solutions.<module>.hidden_tests``."""
MODULE_NAME = "_kit_grading"
"""The kernel-side module's name in the kernel's ``sys.modules``."""
MAX_MESSAGE_CHARS = 10_000
"""The most of an error's name, message or location that a test cell keeps."""
FIRST_MESSAGE_BYTES = 1 << 16
"""The largest first message (ready, or why not) the grader reads from a kernel: it reads it in its
own process, before the check's capped child starts."""


class HiddenTestFormError(ValueError):
    """A hidden block that is not of the one form the grader runs."""


class ReferenceUnavailable(RuntimeError):
    """The grader's process cannot import a hidden test or the reference it compares with."""


class KernelStopped(RuntimeError):
    """The kernel stopped answering the hidden test: it died, or the student's code ended the connection."""


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
    ``from solutions.<module>.hidden_tests import check_<f>`` then ``check_<f>(<f>)``."""
    try:
        body = ast.parse(code).body
    except SyntaxError as error:
        raise HiddenTestFormError(f"the hidden block does not parse: {error}") from None
    if (len(body) == 2 and isinstance(body[0], ast.ImportFrom) and body[0].level == 0
            and HIDDEN_MODULE.fullmatch(body[0].module or "") and len(body[0].names) == 1
            and body[0].names[0].asname is None and isinstance(body[1], ast.Expr)
            and isinstance(body[1].value, ast.Call) and isinstance(body[1].value.func, ast.Name)
            and body[1].value.func.id == body[0].names[0].name and not body[1].value.keywords
            and len(body[1].value.args) == 1 and isinstance(body[1].value.args[0], ast.Name)
            and body[0].names[0].name == f"check_{body[1].value.args[0].id}"):
        return HiddenTest(body[0].module, body[0].names[0].name, body[1].value.args[0].id)
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


def kernel_setup_code() -> str:
    """Code that the grader runs silently in each new grading kernel: it defines the kernel-side
    module (autograder/kernel/side.py, sent as source) as ``sys.modules[MODULE_NAME]``, and binds no
    name in the notebook."""
    source = Path(side.__file__).read_text()
    return (f"(lambda sys, types: sys.modules.__setitem__({MODULE_NAME!r}, (lambda m: (exec(compile({source!r}, "
            f"{side.FILENAME!r}, 'exec'), m.__dict__), m)[1])(types.ModuleType({MODULE_NAME!r}))))"
            "(__import__('sys'), __import__('types'))")


def serve_code(path: str, test: HiddenTest) -> str:
    """Code that the grader runs silently in the kernel for one hidden test: serve the student's function."""
    return f"__import__('sys').modules[{MODULE_NAME!r}].serve({path!r}, {test.blank!r})"


class StudentFunction:
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
        peer = self.peer
        use = (served_calls.ReferenceUse.of(self.reference, self.served, args, kwargs)
               if self.served and self.reference is not None else served_calls.ReferenceUse({}))
        peer.targets = {("served", name): use.answerer(name, function) for name, function in self.served.items()}
        buffers: list[bytes] = []
        payload = peer.codec.encode_arguments(args, kwargs, buffers)
        peer.wire.send({"op": "call", "target": "student", "served": sorted(self.served), **payload}, buffers)
        header, buffers = peer.serve_until_answer()
        print(str(header.get("stdout", "")), end="")
        print(str(header.get("stderr", "")), end="", file=sys.stderr)
        caught = [(str(c), str(m)) for c, m in header.get("warnings", []) if isinstance(c, str)]
        if caught and header.get("op") == "return" and self.warnings_fail:
            raise AssertionError(warning_failure(self.__name__, *caught[0]))
        result = peer.apply_answer(header, buffers, args, kwargs)
        if header.get("op") == "return":
            # what the kernel reports that the call did besides returning (autograder/kernel/side.py)
            changed = [name[:40] for name in header.get("changed") or [] if isinstance(name, str)]
            if changed:
                raise CallRuleBroken(changed_arguments_failure(self.__name__, changed[:5]))
            if header.get("global_random") is True:
                raise CallRuleBroken(global_random_failure(self.__name__))
        for category, message in caught:
            warnings.warn(message, warning_class(category), stacklevel=2)
        return result


class Listener:
    """A Unix socket that one kernel connects to, in a fresh private folder (socket paths are short)."""

    def __init__(self, folder: str | os.PathLike | None = None):
        self.folder = tempfile.mkdtemp(prefix="kit-", dir=folder or "/tmp")
        self.path = os.path.join(self.folder, "s")
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.sock.bind(self.path)
        self.sock.listen(1)

    def accept(self, deadline: float | None, gave_up: Callable[[], bool]) -> socket.socket | None:
        """The kernel's connection, or None if ``gave_up()`` says the kernel will not connect or the deadline passes."""
        while deadline is None or time.monotonic() < deadline:
            self.sock.settimeout(0.05 if deadline is None else max(0.001, min(0.05, deadline - time.monotonic())))
            try:
                connection, _ = self.sock.accept()
            except socket.timeout:
                if gave_up():
                    return None
                continue
            connection.settimeout(None)
            return connection
        return None

    def close(self) -> None:
        self.sock.close()
        shutil.rmtree(self.folder, ignore_errors=True)


def error_output(ename: str, evalue: str, where: str = "") -> NotebookNode:
    """An error output as IPython's minimal traceback shows it: one line, plus where it was raised.
    Each part is cut to MAX_MESSAGE_CHARS: a student's exception can carry megabytes."""
    ename, evalue, where = (cut(text) for text in (ename, evalue, where))
    lines = [f"{ename}: {evalue}"] + ([f"(raised {where})"] if where else [])
    return new_output("error", ename=ename, evalue=evalue, traceback=lines)


def run_check(peer: Peer, test: HiddenTest, check: Callable, earlier: frozenset[str],
              max_chars: int) -> tuple[list[NotebookNode], int, str | None, str | None]:
    """Run ``check`` on the student's function over ``peer``: the outputs the cell gets, how many
    characters the student's function printed (and warned) in all, of which the outputs keep the
    first ``max_chars``, and the slug of the catalogued mistake that the check's diagnosis found
    behind its failure (autograder/hidden_tests/diagnosis.py), or None, and the kind of case that alone
    it was wrong on (autograder/hidden_tests/case_kinds.py), or None: both read from the exception the
    check raised in this process, never from anything the kernel sent.

    The outputs are what the student's function printed, as stdout text (whatever stream it wrote
    to: text from the kernel never scores), then, if the check failed, one error output with the
    check's message: the grader's verdict (autograder/pipeline/verdicts.py) is that there is no
    error. A warning the check let through fails it too, as nbgrader's stderr rule used to. What
    the check returns is not shown: a test cell's score is its verdict, never a value.

    Raises PeerTimeout when the kernel does not answer in time and KernelStopped when it stops
    answering; every other failure is the student's, and becomes an error output.
    """
    out = Capped(max_chars)
    outputs: list[NotebookNode] = []
    mistake = wrong_on = None
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            check(StudentFunction(peer, test.blank, earlier))
        except (PeerTimeout, KernelStopped):
            raise
        except PeerGone:
            raise KernelStopped("the kernel closed the hidden test's connection") from None
        except ProtocolError as error:
            outputs.append(error_output("GradingError", f"The grader could not read your kernel's answer ({error})."))
        except Exception as error:  # noqa: BLE001 (a failing check: its message is the student's feedback)
            notes = getattr(error, "__notes__", [])
            mistake, wrong_on = diagnosed_mistake(error), wrong_only(error)
            outputs.append(error_output(type(error).__name__, "\n".join([str(error), *notes]), getattr(error, "where", "")))
    for w in caught:
        out.write(f"{w.category.__name__}: {w.message}\n")
    if caught and not outputs:
        first = caught[0]
        outputs.append(error_output("AssertionError", warning_failure(test.blank, first.category.__name__, str(first.message))))
    printed = out.getvalue()
    streams = [new_output("stream", name="stdout", text=printed)] if printed else []
    return streams + outputs, out.written, mistake, wrong_on


class Capped(io.TextIOBase):
    """A text stream that keeps the first ``limit`` characters written to it, and counts them all."""

    def __init__(self, limit: int):
        super().__init__()
        self.limit, self.written, self.parts = limit, 0, []

    def writable(self) -> bool:
        return True

    def write(self, text: str) -> int:
        if self.written < self.limit:
            self.parts.append(text[: self.limit - self.written])
        self.written += len(text)
        return len(text)

    def getvalue(self) -> str:
        return "".join(self.parts)


def cut(text: str) -> str:
    """``text``, cut to MAX_MESSAGE_CHARS with a note that says so (an error's message, name or line)."""
    if len(text) <= MAX_MESSAGE_CHARS:
        return text
    dropped = len(text) - MAX_MESSAGE_CHARS
    return f"{text[:MAX_MESSAGE_CHARS]} [... {dropped:,} more characters cut by the grader]"


def connect(listener: Listener, deadline: float | None, gave_up: Callable[[], bool]) -> tuple[Peer | None, str]:
    """Accept the kernel's connection and read its first message: (the peer, "") when the student's
    function is ready, or (None, why not). Raises PeerTimeout if the kernel does not answer in time."""
    tampered = "The hidden test could not reach your function: a cell of the notebook changed or removed the grader's code in the kernel."
    connection = listener.accept(deadline, gave_up)
    if connection is None:
        if deadline is not None and time.monotonic() >= deadline:
            raise PeerTimeout()
        return None, tampered
    wire = Wire(connection)
    wire.deadline, wire.limit = deadline, FIRST_MESSAGE_BYTES
    try:
        header, _ = wire.receive()
    except (PeerGone, ProtocolError):
        header = {}
    wire.limit = side.MAX_MESSAGE_BYTES
    if header.get("op") == "ready":
        return Peer(wire), ""
    connection.close()
    return None, str(header["message"]) if header.get("op") == "missing" else tampered


def stop(peer: Peer) -> None:
    """Tell the kernel that the hidden test is over, and close the connection."""
    with contextlib.suppress(PeerGone, OSError):
        peer.wire.send({"op": "stop"}, [])
    peer.wire.sock.close()

"""Hidden tests run in the grader's process, against the student's function in the grading kernel.

In grading, the kernel never runs a test cell's hidden block (autograder/pipeline/hidden_blocks.py).
``GradingExecute`` runs the cell's visible part in the kernel, then :func:`run_check` runs the block's
``check_f`` here, in the grader's process (in a forked child capped in memory and time,
autograder/pipeline/confined_check.py), where the reference is, on a ``StudentFunction``
(autograder/pipeline/student_function.py): a stand-in whose calls go over a Unix socket
(autograder/pipeline/kernel_connection.py) to the kernel's server (autograder/kernel/server.py), which
calls the student's ``f`` and sends back what it returned. The check's verdict becomes the cell's
outputs: nothing on a pass, the check's error on a failure. Whatever the kernel does, it cannot make a
check pass without returning the reference's values, and it never holds the reference.
"""

from __future__ import annotations

import contextlib
import warnings
from typing import Callable

from nbformat import NotebookNode
from nbformat.v4 import new_output

from autograder.hidden_tests.case_kinds import wrong_only
from autograder.hidden_tests.diagnosis import diagnosed_mistake
from autograder.hidden_tests.isolate import warning_failure
from autograder.kernel.wire import Peer, PeerGone, PeerTimeout, ProtocolError
from autograder.pipeline.hidden_blocks import HiddenTest
from autograder.pipeline.kernel_connection import KernelStopped
from autograder.pipeline.output_caps import Capped, error_output
from autograder.pipeline.student_function import StudentFunction


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

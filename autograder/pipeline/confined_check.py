"""A hidden test's check, run in a child of the grader's process that is capped in memory and time.

A check decodes what the grading kernel sends, and runs the reference on inputs that the kernel
chooses: a blank served to the student's function, or a model function the check passes in, is
called with whatever the student's code passes, sizes included. A hostile kernel could so make the
grader allocate or compute without bound (one served ``initial_cloud(b0, N, rng)`` with N = 10^9, or
one message whose arrays all point at the same buffer), which would stop the grading of the whole
class, or take the machine's memory from every other job. So each check runs in a forked child of
the grader whose address space may grow by at most the kernel's own memory cap (RLIMIT_AS), and
which is killed at the cell's deadline. Whatever the kernel makes it do, the child runs out of memory
or time on its own, the test fails, and the grader goes on. The child sends back only its outputs,
as JSON over a pipe.
"""

from __future__ import annotations

import json
import os
import signal
import time
import traceback
from typing import Callable, NoReturn

import nbformat
from nbformat import NotebookNode

from autograder.forked_child import cap_memory, read_all, write_reply
from autograder.kernel.wire import PeerTimeout
from autograder.pipeline.kernel_connection import KernelStopped
from autograder.pipeline.output_caps import error_output

PASSED_ON = {"PeerTimeout": PeerTimeout, "KernelStopped": KernelStopped}
"""What the check may raise for the grader to handle (the kernel is stuck or gone), by name."""
GRACE_S = 1.0
"""How long after the deadline the child may still send its outputs (it times out by itself first)."""


class CheckFailed(RuntimeError):
    """The check raised something it should not have: a fault of the grader's, not of the student's."""


def run(check: Callable[[], tuple[list[NotebookNode], int, str | None, str | None]], deadline: float | None,
        memory_bytes: int) -> tuple[list[NotebookNode], int, str | None, str | None]:
    """``check()`` run in a forked child of this process, whose address space may grow by at most
    ``memory_bytes`` (0: no cap) and which is killed once ``deadline`` (time.monotonic(); None: none)
    has passed: what ``check()`` returned (outputs, characters printed, diagnosed mistake or None, the
    kind of case alone wrong or None).

    Raises PeerTimeout at the deadline, what the check raised among PASSED_ON, and CheckFailed for
    anything else it raised. A child that dies without an answer (over its memory cap where Python
    could not even raise MemoryError, or a crash) gives the cell an error output that says so.
    """
    read_end, write_end = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(read_end)
        _child(check, write_end, memory_bytes)
    os.close(write_end)
    try:
        answer = read_all(read_end, None if deadline is None else deadline + GRACE_S)
    finally:
        os.close(read_end)
    if answer is None:
        os.kill(pid, signal.SIGKILL)
    _, status = os.waitpid(pid, 0)
    if answer is None:
        raise PeerTimeout()
    try:
        reply = json.loads(answer)
    except ValueError:
        code = os.waitstatus_to_exitcode(status)
        how = f"was stopped by signal {-code}" if code < 0 else f"ended with status {code}"
        return [error_output("GradingError", f"The grader's check of your function {how} before it finished, "
                             "most likely because what your function sent back, or asked the grader to compute, "
                             "needed more memory than a check may use.")], 0, None, None
    if "raised" in reply:
        raise PASSED_ON[reply["raised"]]()
    if "failed" in reply:
        raise CheckFailed(f"The hidden test's check failed in the grader:\n{reply['failed']}")
    mistake, wrong_on = reply.get("mistake"), reply.get("wrong_only")
    return ([nbformat.from_dict(output) for output in reply["outputs"]], int(reply["printed"]),
            mistake if isinstance(mistake, str) else None, wrong_on if isinstance(wrong_on, str) else None)


def _child(check: Callable[[], tuple[list[NotebookNode], int, str | None, str | None]], fd: int,
           memory_bytes: int) -> NoReturn:
    """In the forked child: cap the address space, run ``check``, write the answer to ``fd`` and
    exit (status 0 once the answer is written) without running anything of the parent's: no atexit
    handlers, no finalizers."""
    try:
        cap_memory(memory_bytes)
        try:
            outputs, printed, mistake, wrong_on = check()
            reply: dict = {"outputs": outputs, "printed": printed, "mistake": mistake, "wrong_only": wrong_on}
        except tuple(PASSED_ON.values()) as error:
            reply = {"raised": type(error).__name__}
        except BaseException:  # noqa: BLE001 (the grader's fault: the parent raises it as CheckFailed)
            reply = {"failed": traceback.format_exc()}
        write_reply(fd, reply)
        os._exit(0)
    finally:
        os._exit(1)

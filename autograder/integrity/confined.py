"""The integrity scan, run in a child of the grader's process that is capped in CPU time and memory.

The scan (autograder/integrity/scan.py) reads a submission's code in the grader's process, where a
hostile notebook could make it slow or large: IPython's transform of a cell costs time that grows
with its magic lines times its lines (120 magics among 40,000 lines: minutes), and a syntax tree
costs hundreds of bytes per character of code (a 6 MB list literal took the grader to 9 GB). The
scan's size caps bound the code it parses; this module bounds what parsing it costs, whatever the
code: the scan runs in a forked child whose CPU time (RLIMIT_CPU) and address-space growth
(RLIMIT_AS) are capped, and which is killed if it has not answered by a wall-clock deadline. A scan
that does not finish within them is a finding that costs every blank (its code was not checked);
the grader, its memory and the rest of the class are as they were. The child sends back only its
findings, as JSON over a pipe, and its syntax trees die with it.
"""

from __future__ import annotations

import json
import os
import resource
import signal
import time
import traceback
from typing import NoReturn

from nbformat import NotebookNode

from autograder.forked_child import cap_memory, read_all, write_reply
from autograder.integrity.scan import Finding, static_findings
from autograder.labs import Lab

SCAN_CPU_SECONDS = 10
"""CPU time the scan of one submission may use (a solved notebook's takes under 0.2 s)."""
SCAN_MEMORY_BYTES = 1 << 30
"""How much the scan's child may grow beyond the grader's size (a solved notebook's adds a few MB)."""
SCAN_WALL_SECONDS = 300.0
"""The child is killed if it has not answered by then (CPU time runs slower than the clock on a
loaded machine; this catches a child that waits instead of computing)."""


class ScanFailed(RuntimeError):
    """The scan raised: a fault of the grader's, not of the submission's."""


def confined_findings(nb: NotebookNode, lab: Lab, cpu_seconds: int = SCAN_CPU_SECONDS,
                      memory_bytes: int = SCAN_MEMORY_BYTES, wall_seconds: float = SCAN_WALL_SECONDS) -> list[Finding]:
    """``static_findings(nb, lab)``, computed in a forked child capped at ``cpu_seconds`` of CPU time
    and ``memory_bytes`` of growth and killed after ``wall_seconds``; a scan that exceeds them is one
    finding that costs every blank."""
    read_end, write_end = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(read_end)
        _child(nb, lab, write_end, cpu_seconds, memory_bytes)
    os.close(write_end)
    try:
        answer = read_all(read_end, time.monotonic() + wall_seconds)
    finally:
        os.close(read_end)
    if answer is None:
        os.kill(pid, signal.SIGKILL)
    _, status = os.waitpid(pid, 0)
    try:
        reply = json.loads(answer) if answer is not None else None
    except ValueError:
        reply = None
    if reply is None or "over" in reply:
        code = os.waitstatus_to_exitcode(status)
        if reply is not None:
            how = f"ran out of its {reply['over']}"
        elif answer is None or code in (-signal.SIGXCPU, -signal.SIGKILL):
            how = "ran out of its time"
        else:
            how = f"stopped (status {code})"
        return [Finding("", None, f"The integrity scan of this notebook {how} before it finished (it may use "
                                  f"{cpu_seconds} s of CPU time and {memory_bytes // 2**20:,} MiB of memory), "
                                  "so nothing checked what its code does.")]
    if "failed" in reply:
        raise ScanFailed(f"The integrity scan failed in the grader:\n{reply['failed']}")
    return [Finding(f["cell"], None if f["blanks"] is None else tuple(f["blanks"]), f["reason"])
            for f in reply["findings"]]


def _child(nb: NotebookNode, lab: Lab, fd: int, cpu_seconds: int, memory_bytes: int) -> NoReturn:
    """In the forked child: cap CPU time and address space, scan, write the findings to ``fd`` and
    exit without running anything of the parent's (no atexit handlers, no finalizers)."""
    try:
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
        # a forked child starts with no CPU time of its own: SIGXCPU at the soft limit, SIGKILL 2 s later
        hard_cpu = resource.getrlimit(resource.RLIMIT_CPU)[1]
        hard = cpu_seconds + 2 if hard_cpu == resource.RLIM_INFINITY else min(cpu_seconds + 2, hard_cpu)
        resource.setrlimit(resource.RLIMIT_CPU, (min(cpu_seconds, hard), hard))
        cap_memory(memory_bytes)
        try:
            reply: dict = {"findings": [{"cell": f.cell, "blanks": f.blanks, "reason": f.reason}
                                        for f in static_findings(nb, lab)]}
        except MemoryError:
            reply = {"over": "memory"}
        except RecursionError:  # code nested deeper than the scan's walk of its tree can follow
            reply = {"over": "depth of nesting"}
        except BaseException:  # noqa: BLE001 (the grader's fault: the parent raises it as ScanFailed)
            reply = {"failed": traceback.format_exc()}
        write_reply(fd, reply)
        os._exit(0)
    finally:
        os._exit(1)

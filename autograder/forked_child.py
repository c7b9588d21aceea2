"""What a forked child of the grader and its parent share: the child caps its memory, writes its one
JSON reply to a pipe; the parent reads the reply until the child closes the pipe or a deadline passes.
Used by the confined hidden check (autograder/pipeline/confined_check.py) and the confined integrity
scan (autograder/integrity/confined.py)."""

from __future__ import annotations

import json
import os
import resource
import select
import sys
import time


def cap_memory(memory_bytes: int) -> None:
    """Let this process grow by at most ``memory_bytes`` beyond its size now (RLIMIT_AS, on Linux only:
    elsewhere it is not enforced); 0 leaves it alone."""
    if memory_bytes and sys.platform == "linux":
        size = int(open("/proc/self/statm").read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
        hard = resource.getrlimit(resource.RLIMIT_AS)[1]
        cap = size + memory_bytes if hard == resource.RLIM_INFINITY else min(size + memory_bytes, hard)
        resource.setrlimit(resource.RLIMIT_AS, (cap, hard))


def write_reply(fd: int, reply: dict) -> None:
    """Write ``reply`` as JSON to ``fd``, whole."""
    view = memoryview(json.dumps(reply).encode())
    while view:
        view = view[os.write(fd, view):]


def read_all(fd: int, deadline: float | None) -> bytes | None:
    """Everything the child writes to ``fd`` until it closes it; None if ``deadline`` (monotonic) passes first."""
    parts = []
    while True:
        wait = None if deadline is None else max(0.0, deadline - time.monotonic())
        ready, _, _ = select.select([fd], [], [], wait)
        if not ready:
            return None
        chunk = os.read(fd, 1 << 20)
        if not chunk:
            return b"".join(parts)
        parts.append(chunk)

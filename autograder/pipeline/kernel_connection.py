"""The grader's connection to the kernel's server for one hidden test: a Unix socket that the kernel
connects to, the kernel's first message (ready, or why not), and the end of the test.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import socket
import tempfile
import time
from typing import Callable

from autograder.kernel.wire import MAX_MESSAGE_BYTES, Peer, PeerGone, PeerTimeout, ProtocolError, Wire

FIRST_MESSAGE_BYTES = 1 << 16
"""The largest first message (ready, or why not) the grader reads from a kernel: it reads it in its
own process, before the check's capped child starts."""


class KernelStopped(RuntimeError):
    """The kernel stopped answering the hidden test: it died, or the student's code ended the connection."""


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
    wire.limit = MAX_MESSAGE_BYTES
    if header.get("op") == "ready":
        return Peer(wire), ""
    connection.close()
    return None, str(header["message"]) if header.get("op") == "missing" else tampered


def stop(peer: Peer) -> None:
    """Tell the kernel that the hidden test is over, and close the connection."""
    with contextlib.suppress(PeerGone, OSError):
        peer.wire.send({"op": "stop"}, [])
    peer.wire.sock.close()

"""The grading kernel's server for a hidden test: it calls the student's function for the grader.

For a hidden test of blank ``f``, the grader runs ``serve`` silently in the kernel
(autograder/pipeline/kernel_code.py): it connects to the grader's socket and answers each call the
grader's check makes of ``f`` by calling the student's ``f`` from the notebook, over the wire
(autograder/kernel/wire.py). Partial credit stays isolated: inside the kernel, the student's ``f``
sees, in place of the other blanks it calls, stand-ins that the grader answers with the reference,
only while that test runs, and never for ``f`` itself.

Like the wire, this file is self-contained: the grader sends its source into each grading kernel, where
it is the module ``_kit_grading`` and imports the wire as ``_kit_grading.wire``, by the relative import
below; in the grader it is ``autograder.kernel.server``, and the same import finds ``autograder.kernel.wire``.
"""

from __future__ import annotations

import builtins
import socket
import sys
import types

from .wire import Peer, PeerGone, ProtocolError, RaisedElsewhere, Wire


NOT_SERVED = "NotServed"
"""What the grader raises for a call of a served blank that it leaves to the student's own blank."""


def _served_or_own(peer: Peer, name: str, namespace: dict) -> types.FunctionType:
    """The stand-in for the served blank ``name``: the grader answers the calls that the reference
    makes too; the student's own ``name`` (from the notebook) answers the others."""
    stub = peer.stub(("served", name))

    def served_or_own(*args, **kwargs):
        try:
            return stub(*args, **kwargs)
        except RaisedElsewhere as error:
            if type(error).__name__ != NOT_SERVED:
                raise
        own = namespace.get(name)
        if not callable(own):
            raise NameError(f"name {name!r} is not defined")
        return own(*args, **kwargs)

    served_or_own.__name__ = served_or_own.__qualname__ = name
    return served_or_own


def serve(path: str, name: str, namespace: dict | None = None) -> None:
    """In the grading kernel: connect to the grader at ``path`` and call the student's function
    ``name`` (from the notebook's namespace) for the grader until it says stop.

    Each call is made on a copy of the function that sees, for each blank the call's message lists
    as served, a stand-in that the grader answers with the reference; the notebook's own names are
    left alone.
    """
    if namespace is None:
        namespace = sys.modules["__main__"].__dict__
        shell = getattr(builtins, "get_ipython", None)
        if shell is not None:
            namespace = shell().user_ns
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    sock.connect(path)
    wire = Wire(sock)
    try:
        function = namespace.get(name)
        if not isinstance(function, types.FunctionType):
            what = "not defined" if function is None else f"a {type(function).__name__}, not a function"
            wire.send({"op": "missing", "message": f"{name} is {what}: define it with `def {name}(...)` in its answer cell."}, [])
            return
        peer = Peer(wire, capture_output=True)
        wire.send({"op": "ready"}, [])
        while True:
            header, buffers = wire.receive()
            if header.get("op") == "stop":
                return
            if header.get("op") != "call":
                raise ProtocolError(f"an unexpected message {header.get('op')!r}")
            served = [str(other) for other in header.get("served", []) if other != name]
            stand_ins = {other: _served_or_own(peer, other, namespace) for other in served}
            copy = types.FunctionType(function.__code__, {**function.__globals__, **stand_ins}, function.__name__,
                                      function.__defaults__, function.__closure__)
            copy.__kwdefaults__ = function.__kwdefaults__
            peer.targets["student"] = copy
            peer.answer(header, buffers)
    except PeerGone:
        return
    finally:
        sock.close()

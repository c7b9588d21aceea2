"""The wire that the grader and the grading kernel speak during a hidden test: framing (``Wire``),
values (``Codec``) and calls both ways (``Peer``).

The grader never runs hidden tests in the student's kernel. For a hidden test of blank ``f``, the
grader (autograder/pipeline/check_runner.py) runs the check ``check_f`` in its own process, with the
reference, and hands it a stand-in for the student's ``f`` (autograder/pipeline/student_function.py);
each call of the stand-in sends the inputs over a Unix socket to the kernel, where the kernel's server
(autograder/kernel/server.py) calls the student's ``f`` and sends back only what it returned (and
what it wrote into a dict, a random generator or an Axes it was given). The kernel therefore sees the
hidden cases' inputs, never the reference, the expected values or the checks.

This file is self-contained (the standard library and NumPy; matplotlib only for a plot blank): the
grader sends its source into each grading kernel with the server's (autograder/pipeline/kernel_code.py),
so the kernel never imports ``autograder``. The grader imports the same file for its end of the wire.

The wire carries only data: numbers, strings, NumPy arrays of numbers, tuples, lists, dicts, NumPy
random generators (their state), the ``course`` package's dataclasses, what a Matplotlib Axes shows
(lines, filled bands, labels, legend), exceptions and warnings by name and message, and references
to functions that the other side calls back. Nothing is unpickled: a message from a student's kernel
can never run code in the grader.
"""

from __future__ import annotations

import builtins
import contextlib
import dataclasses
import hashlib
import io
import json
import keyword
import linecache
import re
import socket
import struct
import sys
import time
import types
import warnings

import numpy as np

FILENAME = "<estimation-lab-kit grading>"
"""The file name the kernel gives the wire's and the server's code (their frames are left out of a student's traceback)."""
MAX_MESSAGE_BYTES = 1 << 30
"""The largest message either side accepts (1 GiB): a larger one is a protocol error."""
GENERATORS = ("PCG64", "PCG64DXSM")
"""The bit generators whose state crosses the wire: those whose state holds only numbers. MT19937, Philox and SFC64
keep arrays in theirs, which JSON does not take (a review of issue 30: one returned from the kernel ended its
connection, and the student was told that their code had); they are refused as unsendable, with a message."""
EXCEPTIONS_BY_NAME = {"LinAlgError": np.linalg.LinAlgError}
"""Exceptions outside ``builtins`` that the receiving side re-raises as themselves."""


LONE_SURROGATE = re.compile(rb"\\u[dD][89a-fA-F][0-9a-fA-F]{2}")


def _valid_unicode(text: bytes) -> bytes:
    """A JSON text whose string escapes of lone UTF-16 surrogates are replaced by U+FFFD. JSON allows them, but
    a string holding one cannot be written as UTF-8: a student's function that printed chr(0xD800) during a
    hidden test made nbgrader fail to write the graded notebook (adversarial review of issue 31). An escaped
    surrogate pair (an emoji) is kept."""
    if not LONE_SURROGATE.search(text):
        return text
    decoded = json.loads(text)
    return json.dumps(replace_lone_surrogates(decoded), ensure_ascii=True).encode()


def replace_lone_surrogates(value):
    """``value`` (a string, or lists and dicts of them and of other values) with each lone UTF-16 surrogate in its
    strings replaced by U+FFFD: what no file can store as UTF-8. The grader's other texts (a submitted notebook,
    a note that names a file) use it too."""
    if isinstance(value, str):
        return "".join("\ufffd" if "\ud800" <= ch <= "\udfff" else ch for ch in value)
    if isinstance(value, list):
        return [replace_lone_surrogates(v) for v in value]
    if isinstance(value, dict):
        return {replace_lone_surrogates(k): replace_lone_surrogates(v) for k, v in value.items()}
    return value


class ProtocolError(Exception):
    """A message that does not follow the wire format (a broken or tampered peer)."""


class PeerGone(Exception):
    """The other side closed the connection (in the grader: the kernel died)."""


class PeerTimeout(Exception):
    """No answer before the deadline."""


class Unsendable(TypeError):
    """A value that the wire cannot carry."""


class RaisedElsewhere(Exception):
    """An exception raised on the other side whose type has no counterpart here; its name is kept."""


# -- framing -----------------------------------------------------------------------------------


class Wire:
    """Length-prefixed messages over a connected stream socket: a JSON header and binary buffers."""

    def __init__(self, sock: socket.socket):
        self.sock = sock
        self.deadline: float | None = None
        """time.monotonic() after which receive raises PeerTimeout (None: wait for ever)."""
        self.limit = MAX_MESSAGE_BYTES
        """The largest message receive accepts; a larger one is a ProtocolError, raised before it is read."""

    def send(self, header: dict, buffers: list[bytes]) -> None:
        data = json.dumps(header).encode()
        parts = [struct.pack("!QQ", len(data), len(buffers)), data]
        for buffer in buffers:
            parts += [struct.pack("!Q", len(buffer)), buffer]
        try:
            self.sock.sendall(b"".join(parts))
        except OSError as error:
            raise PeerGone(str(error)) from None

    def receive(self) -> tuple[dict, list[bytes]]:
        size, count = struct.unpack("!QQ", self._exactly(16))
        if size > self.limit or count > 1_000_000:
            raise ProtocolError("a message larger than the wire allows")
        try:
            header = json.loads(_valid_unicode(self._exactly(size)))
        except (ValueError, RecursionError):  # not JSON, or nested deeper than Python's stack
            raise ProtocolError("a header that is not JSON") from None
        if not isinstance(header, dict):
            raise ProtocolError("a header that is not a JSON object")
        buffers, total = [], size
        for _ in range(count):
            (length,) = struct.unpack("!Q", self._exactly(8))
            total += length
            if total > self.limit:
                raise ProtocolError("a message larger than the wire allows")
            buffers.append(self._exactly(length))
        return header, buffers

    def _exactly(self, n: int) -> bytes:
        data = bytearray()
        while len(data) < n:
            if self.deadline is not None:
                left = self.deadline - time.monotonic()
                if left <= 0:
                    raise PeerTimeout()
                self.sock.settimeout(left)
            try:
                chunk = self.sock.recv(min(n - len(data), 1 << 20))
            except socket.timeout:
                raise PeerTimeout() from None
            except OSError as error:
                raise PeerGone(str(error)) from None
            if not chunk:
                raise PeerGone("the connection was closed")
            data += chunk
        return bytes(data)


# -- values ------------------------------------------------------------------------------------


def _is_axes(value) -> bool:
    axes = sys.modules.get("matplotlib.axes")
    return axes is not None and isinstance(value, axes.Axes)


def _new_axes():
    from matplotlib.figure import Figure

    return Figure().subplots()


class Codec:
    """Turns values into (JSON node, buffers) and back, for one side of one connection.

    ``callables`` holds this side's functions that the other side may call back, by number;
    ``axes`` the Axes that travelled as arguments, by number, so that a returned Axes is the same
    object that was passed in.
    """

    def __init__(self):
        self.callables: list = []
        self.axes: dict[int, object] = {}

    # encoding
    def encode(self, value, buffers: list[bytes]):
        if isinstance(value, (np.ndarray, np.generic)):
            array = np.asarray(value)
            if array.dtype.kind not in "biufc" or array.dtype.fields is not None:
                raise Unsendable(f"an array of {array.dtype}")
            buffers.append(np.ascontiguousarray(array).tobytes())
            return {"t": "array" if isinstance(value, np.ndarray) else "scalar", "dtype": array.dtype.str,
                    "shape": list(array.shape), "buffer": len(buffers) - 1}
        if value is None or isinstance(value, (bool, int, float, str)):
            return {"t": "py", "v": value}
        if isinstance(value, complex):
            return {"t": "complex", "v": [value.real, value.imag]}
        if isinstance(value, (tuple, list)):
            return {"t": type(value).__name__, "items": [self.encode(item, buffers) for item in value]}
        if isinstance(value, dict):
            if not all(isinstance(key, (str, int)) and not isinstance(key, bool) for key in value):
                raise Unsendable("a dict whose keys are not strings or integers")
            return {"t": "dict", "items": [[key, self.encode(item, buffers)] for key, item in value.items()]}
        if isinstance(value, np.random.Generator):
            name = type(value.bit_generator).__name__
            if name not in GENERATORS:
                raise Unsendable(f"a random generator with bit generator {name}")
            return {"t": "generator", "bit_generator": name, "state": value.bit_generator.state,
                    "seed_sequence": _seed_sequence_json(value.bit_generator.seed_seq)}
        if _is_axes(value):
            number = next((n for n, ax in self.axes.items() if ax is value), None)
            if number is not None:
                return {"t": "axes", "number": number, "drawing": _drawing(value, self, buffers)}
            return {"t": "axes", "number": None, "drawing": _drawing(value, self, buffers)}
        if dataclasses.is_dataclass(value) and not isinstance(value, type):
            cls = type(value)
            if not cls.__module__.startswith("course."):
                raise Unsendable(f"a {cls.__qualname__} object")
            return {"t": "dataclass", "module": cls.__module__, "name": cls.__qualname__,
                    "fields": {f.name: self.encode(getattr(value, f.name), buffers) for f in dataclasses.fields(value)}}
        if callable(value):
            self.callables.append(value)
            return {"t": "callable", "number": len(self.callables) - 1}
        raise Unsendable(f"a {type(value).__name__} object")

    def encode_arguments(self, args: tuple, kwargs: dict, buffers: list[bytes]) -> dict:
        """Arguments, with each Axes among them numbered (a fresh one is made on the other side)."""
        for value in (*args, *kwargs.values()):
            if _is_axes(value):
                self.axes[len(self.axes)] = value
        return {"args": [self.encode(a, buffers) for a in args],
                "kwargs": {k: self.encode(v, buffers) for k, v in kwargs.items()}}

    # decoding
    def decode(self, node, buffers: list[bytes], peer: "Peer"):
        if not isinstance(node, dict):
            raise ProtocolError("a value that is not a node")
        kind = node.get("t")
        if kind == "py":
            value = node.get("v")
            if value is not None and not isinstance(value, (bool, int, float, str)):
                raise ProtocolError("a plain value that is not plain")
            return value
        if kind == "complex":
            real, imag = node["v"]
            return complex(float(real), float(imag))
        if kind in ("array", "scalar"):
            dtype = np.dtype(str(node["dtype"]))
            if dtype.kind not in "biufc" or dtype.fields is not None:
                raise ProtocolError(f"an array of {dtype}")
            shape = tuple(int(n) for n in node["shape"])
            data = _buffer(buffers, node["buffer"])
            if any(n < 0 for n in shape) or len(data) != dtype.itemsize * int(np.prod(shape, dtype=np.int64)):
                raise ProtocolError("an array whose size does not match its shape")
            array = np.frombuffer(data, dtype=dtype).reshape(shape).copy()
            return array if kind == "array" else array[()]
        if kind in ("tuple", "list"):
            items = [self.decode(item, buffers, peer) for item in node["items"]]
            return tuple(items) if kind == "tuple" else items
        if kind == "dict":
            out = {}
            for key, item in node["items"]:
                if not isinstance(key, (str, int)) or isinstance(key, bool):
                    raise ProtocolError("a dict key that is not a string or an integer")
                out[key] = self.decode(item, buffers, peer)
            return out
        if kind == "generator":
            generator = np.random.Generator(_bit_generator(node))
            return generator
        if kind == "axes":
            number = node.get("number")
            ax = self.axes.get(number) if isinstance(number, int) else None
            if ax is None:
                ax = _new_axes()
            else:
                ax.cla()  # the drawing is the Axes' whole content: the write-back and the return draw it once
            _draw(ax, node.get("drawing"), self, buffers, peer)
            return ax
        if kind == "dataclass":
            return _dataclass(node, self, buffers, peer)
        if kind == "callable":
            return peer.stub(("callable", int(node["number"])))
        raise ProtocolError(f"an unknown kind of value {kind!r}")

    def decode_arguments(self, payload: dict, buffers: list[bytes], peer: "Peer") -> tuple[tuple, dict]:
        """Arguments, with each numbered Axes made fresh and remembered for the call's answer."""
        args = tuple(self._argument(node, buffers, peer) for node in payload.get("args", []))
        kwargs = {str(k): self._argument(node, buffers, peer) for k, node in payload.get("kwargs", {}).items()}
        return args, kwargs

    def _argument(self, node, buffers, peer):
        if isinstance(node, dict) and node.get("t") == "axes":
            number = len(self.axes)
            self.axes[number] = ax = _new_axes()
            _draw(ax, node.get("drawing"), self, buffers, peer)
            return ax
        return self.decode(node, buffers, peer)


def _buffer(buffers: list[bytes], index) -> bytes:
    if not isinstance(index, int) or not 0 <= index < len(buffers):
        raise ProtocolError("a reference to a buffer that is not there")
    return buffers[index]


MAX_SPAWNED = 1 << 30
"""The most children a generator that crosses the wire may have spawned (NumPy 2.4 hangs spawning near 2**32)."""
_spawned_elsewhere: dict[int, tuple[np.random.SeedSequence, int]] = {}
"""id of a seed sequence -> (it, how many children the other side has spawned from it in all): counted here, not
spawned, since the other side says the number (an adversarial review: a kernel that said 2**20 made the grader spawn
that many children, 13 s and 441 MB a call). The seed sequence is kept, so that its id is not reused."""


def _children_spawned(seed_seq: np.random.SeedSequence) -> int:
    """How many children ``seed_seq`` has spawned, here or, from a copy sent there, on the other side."""
    elsewhere = _spawned_elsewhere.get(id(seed_seq))
    return max(seed_seq.n_children_spawned, elsewhere[1] if elsewhere is not None and elsewhere[0] is seed_seq else 0)


def _seed_sequence_json(seed_seq) -> dict | None:
    """The seed sequence of a generator, which its spawn() and its children's seeds come from (a final review of
    issue 30: without it, the generator rebuilt on the other side spawned other children on every call). Its
    entropy travels as a one-way digest: the same generator gives the same children on the other side, which
    does not learn the entropy (the grader's is a digest of the submission's seed: autograder/hidden_tests/cases.py)."""
    if not isinstance(seed_seq, np.random.SeedSequence):
        return None
    digest = hashlib.sha256(repr((seed_seq.entropy, tuple(seed_seq.spawn_key))).encode()).digest()
    return {"entropy": int.from_bytes(digest[:16], "big"), "spawn_key": [], "pool_size": int(seed_seq.pool_size),
            "n_children_spawned": _children_spawned(seed_seq)}


def _spawn_as_many(seed_seq, rebuilt) -> None:
    """Count for ``seed_seq`` the children the call spawned from its copy ``rebuilt`` (at most MAX_SPAWNED in all),
    so that the next call spawns new ones, as the student's own generator does."""
    if isinstance(seed_seq, np.random.SeedSequence) and isinstance(rebuilt, np.random.SeedSequence):
        count = min(rebuilt.n_children_spawned, MAX_SPAWNED)
        if count > _children_spawned(seed_seq):
            _spawned_elsewhere[id(seed_seq)] = (seed_seq, count)


def _seed_sequence(node) -> np.random.SeedSequence | None:
    """A seed sequence sent by ``_seed_sequence_json``, checked (None: a fresh one)."""
    if node is None:
        return None
    try:
        entropy, key = node["entropy"], node["spawn_key"]
        numbers = [entropy] if isinstance(entropy, int) else list(entropy)
        if (len(numbers) > 64 or len(key) > 64 or not all(isinstance(n, int) and 0 <= n < 2**256 for n in [*numbers, *key])
                or not isinstance(node["pool_size"], int) or not 4 <= node["pool_size"] <= 64
                or not isinstance(node["n_children_spawned"], int) or not 0 <= node["n_children_spawned"] <= MAX_SPAWNED):
            raise ValueError("out of range")
        return np.random.SeedSequence(entropy, spawn_key=tuple(key), pool_size=node["pool_size"],
                                      n_children_spawned=node["n_children_spawned"])
    except (TypeError, ValueError, KeyError) as error:
        raise ProtocolError(f"a seed sequence that NumPy refuses ({error})") from None


def _bit_generator(node: dict):
    name = node.get("bit_generator")
    if name not in GENERATORS:
        raise ProtocolError(f"a bit generator {name!r}")
    bit_generator = getattr(np.random, name)(_seed_sequence(node.get("seed_sequence")))
    try:
        bit_generator.state = node["state"]
    except (TypeError, ValueError, KeyError, OverflowError) as error:
        raise ProtocolError(f"a random generator state that NumPy refuses ({error})") from None
    return bit_generator


def _dataclass(node: dict, codec: Codec, buffers, peer):
    module_name, name = str(node.get("module")), str(node.get("name"))
    module = sys.modules.get(module_name)
    if not module_name.startswith("course.") or module is None:
        raise ProtocolError(f"a dataclass from {module_name}")
    cls = getattr(module, name, None)
    if not (isinstance(cls, type) and dataclasses.is_dataclass(cls)):
        raise ProtocolError(f"{module_name}.{name} is not a dataclass")
    fields = {f.name for f in dataclasses.fields(cls)}
    values = {str(k): codec.decode(v, buffers, peer) for k, v in node.get("fields", {}).items()}
    if set(values) != fields:
        raise ProtocolError(f"the fields of {name}")
    return cls(**values)


def _drawing(ax, codec: Codec, buffers: list[bytes]) -> dict:
    """What an Axes shows: its lines and filled regions (data and labels), axis labels, title, legend."""
    from matplotlib.collections import PolyCollection

    legend = ax.get_legend()
    return {
        "lines": [{"xy": codec.encode(np.asarray(line.get_xydata(), dtype=float), buffers), "label": str(line.get_label())}
                  for line in ax.get_lines()],
        "bands": [{"paths": [codec.encode(np.asarray(path.vertices, dtype=float), buffers) for path in band.get_paths()],
                   "label": str(band.get_label())}
                  for band in ax.collections if isinstance(band, PolyCollection)],
        "xlabel": ax.get_xlabel(), "ylabel": ax.get_ylabel(), "title": _title(ax),
        "legend": None if legend is None else [text.get_text() for text in legend.get_texts()],
    }


def _draw(ax, drawing, codec: Codec, buffers, peer) -> None:
    """Draw ``drawing`` (from ``_drawing``) on ``ax``: the same data, labels and legend entries."""
    if not drawing:
        return
    from matplotlib.collections import PolyCollection

    for line in drawing.get("lines", []):
        xy = np.asarray(codec.decode(line["xy"], buffers, peer), dtype=float).reshape(-1, 2)
        ax.plot(xy[:, 0], xy[:, 1], label=str(line.get("label", "")))
    for band in drawing.get("bands", []):
        paths = [np.asarray(codec.decode(p, buffers, peer), dtype=float).reshape(-1, 2) for p in band.get("paths", [])]
        ax.add_collection(PolyCollection(paths, closed=False, label=str(band.get("label", ""))))  # the vertices as drawn
    ax.set_xlabel(str(drawing.get("xlabel", "")))
    ax.set_ylabel(str(drawing.get("ylabel", "")))
    ax.set_title(str(drawing.get("title", "")))
    if isinstance(drawing.get("legend"), list):
        from matplotlib.lines import Line2D

        # the legend's own entries, whatever made them: labels on the artists, or handles and labels given to
        # ax.legend(handles, labels); ax.legend() alone found no labelled artist in the second case (and warned)
        texts = [str(text) for text in drawing["legend"][:100]]
        ax.legend(handles=[Line2D([], []) for _ in texts], labels=texts)


# -- calls ---------------------------------------------------------------------------------------


def exception_class(name: str) -> type:
    """The exception class that ``name`` stands for here: a builtin or a known NumPy one, or a
    subclass of RaisedElsewhere with that name."""
    found = getattr(builtins, name, None)
    if isinstance(found, type) and issubclass(found, Exception):
        return found
    if name in EXCEPTIONS_BY_NAME:
        return EXCEPTIONS_BY_NAME[name]
    if not name.isidentifier() or keyword.iskeyword(name):
        name = "Exception"
    return type(name, (RaisedElsewhere,), {})


def warning_class(name: str) -> type:
    """The warning category that ``name`` stands for here (UserWarning if it is not a builtin one)."""
    found = getattr(builtins, name, None)
    return found if isinstance(found, type) and issubclass(found, Warning) else UserWarning


def _where(error: BaseException, function_name: str) -> str:
    """"in your f, line 3: x = ..." for the last frame of the traceback in a notebook cell, or ""."""
    frames = [frame for frame in _frames(error.__traceback__)
              if frame[0] != FILENAME and ("ipykernel" in frame[0] or frame[0].startswith("<"))]
    if not frames:
        return ""
    filename, lineno, name = frames[-1]
    code = linecache.getline(filename, lineno).strip()
    return f"in {name if name != function_name else 'your ' + name}, line {lineno}" + (f": {code}" if code else "")


def _frames(tb):
    while tb is not None:
        code = tb.tb_frame.f_code
        yield code.co_filename, tb.tb_lineno, code.co_name
        tb = tb.tb_next


class Peer:
    """One side of a connection: makes calls to the other side and answers the other side's calls.

    ``targets`` maps what the other side may call here ("student" for the student's function in the
    kernel, ("served", name) for a reference blank in the grader) to the function.
    """

    def __init__(self, wire: Wire, targets: dict | None = None, capture_output: bool = False):
        self.wire = wire
        self.codec = Codec()
        self.targets = dict(targets or {})
        self.capture_output = capture_output
        """Capture what calls answered here print and warn, and send it with the answer (the kernel)."""

    def stub(self, target) -> types.FunctionType:
        """A function that calls ``target`` on the other side."""
        peer = self

        def call_other_side(*args, **kwargs):
            return peer.call(target, args, kwargs)

        return call_other_side

    def call(self, target, args: tuple, kwargs: dict, **options):
        """Call ``target`` on the other side; answer its calls meanwhile; return what it returned.

        Returns the decoded answer, after writing back into the dicts, generators and Axes among
        the arguments what the call wrote into them. Raises what the call raised.
        """
        header, buffers = self.exchange(target, args, kwargs, **options)
        return self.apply_answer(header, buffers, args, kwargs)

    def exchange(self, target, args: tuple, kwargs: dict, answering: dict | None = None,
                 **options) -> tuple[dict, list[bytes]]:
        """Send the call of ``target`` (with ``options`` in its message), and answer the other side's calls
        until the call's answer arrives; returns that answer's header and buffers, not yet applied
        (``apply_answer``). ``answering``, when given, becomes ``targets``: what the other side may call here."""
        if answering is not None:
            self.targets = dict(answering)
        buffers: list[bytes] = []
        payload = self.codec.encode_arguments(args, kwargs, buffers)
        self.wire.send({"op": "call", "target": _target_json(target), **payload, **options}, buffers)
        return self.serve_until_answer()

    def serve_until_answer(self) -> tuple[dict, list[bytes]]:
        """Receive messages, answering calls, until an answer ("return" or "raise") arrives."""
        while True:
            header, buffers = self.wire.receive()
            op = header.get("op")
            if op in ("return", "raise"):
                return header, buffers
            if op == "call":
                self.answer(header, buffers)
            else:
                raise ProtocolError(f"an unexpected message {op!r}")

    def answer(self, header: dict, buffers: list[bytes]) -> None:
        """Run the call in ``header`` here and send its answer."""
        target = _target_key(header.get("target"))
        function = self.targets.get(target)
        if function is None and isinstance(target, tuple) and target[0] == "callable":
            number = target[1]
            function = self.codec.callables[number] if 0 <= number < len(self.codec.callables) else None
        if function is None:
            self.wire.send({"op": "raise", "type": "RuntimeError", "message": f"nothing to call as {target!r}"}, [])
            return
        args, kwargs = self.codec.decode_arguments(header, buffers, self)
        given = arrays_given(args, kwargs)
        drawn = global_random_state()
        out, err = io.StringIO(), io.StringIO()
        with contextlib.ExitStack() as stack:
            caught = []
            if self.capture_output:
                stack.enter_context(contextlib.redirect_stdout(out))
                stack.enter_context(contextlib.redirect_stderr(err))
                caught = stack.enter_context(warnings.catch_warnings(record=True))
                warnings.simplefilter("always")
            try:
                result = function(*args, **kwargs)
            except Exception as error:  # noqa: BLE001 (the other side gets every error, by name)
                reply, reply_buffers = {"op": "raise", "type": type(error).__name__, "message": str(error),
                                        "where": _where(error, getattr(function, "__name__", ""))}, []
            else:
                reply_buffers: list[bytes] = []
                try:
                    reply = {"op": "return", "value": self.codec.encode(result, reply_buffers),
                             "written": self._written(args, kwargs, reply_buffers),
                             "changed": changed_names(function, given, args, kwargs),
                             "global_random": uses_a_generator(args, kwargs) and global_random_state() != drawn}
                except Unsendable as error:
                    what = getattr(function, "__name__", "the function")
                    reply, reply_buffers = {"op": "raise", "type": "TypeError", "where": "", "message": (
                        f"{what} returned {error}, which the grader cannot compare: return numbers, NumPy "
                        "arrays of numbers, and tuples, lists or dicts of them.")}, []
        reply["stdout"], reply["stderr"] = out.getvalue(), err.getvalue()
        reply["warnings"] = [[w.category.__name__, str(w.message)] for w in caught]
        self.wire.send(reply, reply_buffers)

    def _written(self, args: tuple, kwargs: dict, buffers: list[bytes]) -> dict:
        """The arguments a call may write into (dicts, random generators, Axes), as they are now."""
        written = {}
        for key, value in [*enumerate(args), *kwargs.items()]:
            if isinstance(value, (dict, np.random.Generator)) or _is_axes(value):
                written[str(key)] = self.codec.encode(value, buffers)
        return written

    def apply_answer(self, header: dict, buffers: list[bytes], args: tuple, kwargs: dict):
        """Write back what the call wrote into its arguments, then return its value or raise its error."""
        if header.get("op") == "raise":
            cls = exception_class(str(header.get("type", "Exception")))
            error = cls(str(header.get("message", "")))
            error.where = str(header.get("where", ""))
            raise error
        for key, node in (header.get("written") or {}).items():
            target = args[int(key)] if key.isdigit() and int(key) < len(args) else kwargs.get(key)
            if isinstance(target, dict):
                value = self.codec.decode(node, buffers, self)
                if not isinstance(value, dict):
                    raise ProtocolError("a dict argument that came back as something else")
                target.clear()
                target.update(value)
            elif isinstance(target, np.random.Generator) and isinstance(node, dict) and node.get("t") == "generator":
                rebuilt = _bit_generator(node)
                if type(rebuilt) is not type(target.bit_generator):
                    raise ProtocolError(f"a {type(rebuilt).__name__} state for a {type(target.bit_generator).__name__}")
                target.bit_generator.state = rebuilt.state
                _spawn_as_many(target.bit_generator.seed_seq, rebuilt.seed_seq)
            elif _is_axes(target) and isinstance(node, dict) and node.get("t") == "axes":
                self.codec.decode(node, buffers, self)  # draws on the numbered Axes, which is target
        return self.codec.decode(header.get("value"), buffers, self)


def arrays_given(args: tuple, kwargs: dict) -> dict:
    """A copy of each NumPy array argument of a call, by position or keyword, to see what the call wrote into."""
    return {key: value.copy() for key, value in [*enumerate(args), *kwargs.items()] if isinstance(value, np.ndarray)}


def changed_names(function, given: dict, args: tuple, kwargs: dict) -> list[str]:
    """The names of the array arguments that a call changed in place (a positional one by its parameter's name)."""
    changed = []
    for key, before in given.items():
        after = args[key] if isinstance(key, int) else kwargs[key]
        same = before.shape == after.shape and np.array_equal(before, after, equal_nan=before.dtype.kind in "fc")
        if not same:
            changed.append(_parameter_name(function, key) if isinstance(key, int) else str(key))
    return changed


def _parameter_name(function, position: int) -> str:
    """The name of a function's positional parameter, or "argument <n>" if it has none."""
    code = getattr(function, "__code__", None)
    names = code.co_varnames[:code.co_argcount] if code is not None else ()
    return names[position] if position < len(names) else f"argument {position + 1}"


def uses_a_generator(args: tuple, kwargs: dict) -> bool:
    return any(isinstance(value, np.random.Generator) for value in [*args, *kwargs.values()])


def global_random_state() -> tuple:
    """Where NumPy's global generator (np.random.standard_normal, np.random.choice, ...) stands."""
    state = np.random.get_state(legacy=False)
    # the position in the key, and the Gaussian that a legacy standard_normal keeps for its next call
    return int(state["state"]["pos"]), state["state"]["key"].tobytes(), int(state["has_gauss"]), float(state["gauss"])


def _title(ax) -> str:
    """An Axes' title, wherever it sits (ax.set_title(..., loc="left") is one too)."""
    return next((title for title in (ax.get_title(loc) for loc in ("center", "left", "right")) if title.strip()), "")


def _target_json(target):
    return list(target) if isinstance(target, tuple) else target


def _target_key(target):
    if isinstance(target, list) and len(target) == 2 and isinstance(target[0], str):
        return (target[0], target[1])
    if isinstance(target, str):
        return target
    raise ProtocolError(f"a call target {target!r}")

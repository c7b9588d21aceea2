"""Hidden tests compare in the grader's process (autograder/pipeline/check_runner.py) against the student's
function in the kernel (autograder/kernel/server.py), over the wire (autograder/kernel/wire.py).

Here the kernel's side runs in a thread of the test process, serving functions from a plain dict
as the notebook's namespace, over a real Unix socket: what crosses the wire, what comes back, what
the student's function can reach, and what a hostile kernel's messages can do to the grader. The
grading round trip (tests/test_round_trip.py) runs the same code in real grading kernels.
"""

from __future__ import annotations

import json
import linecache
import socket
import struct
import threading
import time
import warnings

import numpy as np
import pytest
from matplotlib.figure import Figure

from autograder import cells
from autograder.pipeline import hidden_blocks, kernel_connection, served_calls
from autograder.hidden_tests import diagnosis
from autograder.kernel import server, wire
from autograder.pipeline.hidden_blocks import HiddenTest, HiddenTestFormError
from autograder.pipeline.student_function import StudentFunction
from autograder.hidden_tests.isolate import isolate
from autograder.kernel.wire import Codec, Peer, ProtocolError, Wire
from course.falling_object import FilterHistory
from course.starship import check_band_plot
from random_draws import random_draws


class Kernel:
    """The kernel's side of one hidden test, in a thread, serving ``namespace[name]``."""

    def __init__(self, namespace: dict, name: str):
        self.listener = kernel_connection.Listener()
        self.thread = threading.Thread(target=server.serve, args=(self.listener.path, name, namespace),
                                       daemon=True)
        self.thread.start()
        self.peer, self.why_not = kernel_connection.connect(self.listener, None, lambda: not self.thread.is_alive())

    def close(self) -> None:
        if self.peer is not None:
            kernel_connection.stop(self.peer)
        self.thread.join(10)
        self.listener.close()


@pytest.fixture
def kernel():
    opened = []

    def start(namespace: dict, name: str, earlier: frozenset = frozenset()):
        k = Kernel(namespace, name)
        opened.append(k)
        return k if k.peer is None else StudentFunction(k.peer, name, frozenset(earlier))

    yield start
    for k in opened:
        k.close()


def _define(source: str, **names) -> dict:
    """The namespace of a notebook cell that ran ``source`` (its lines known to linecache, as IPython's are)."""
    filename = f"/tmp/ipykernel_0/{abs(hash(source))}.py"
    linecache.cache[filename] = (len(source), None, source.splitlines(True), filename)
    namespace = {"np": np, **names}
    exec(compile(source, filename, "exec"), namespace)
    return namespace


def test_values_cross_exactly(kernel):
    """Arrays of every numeric kind come back bit for bit, with their dtype and shape; NaN, inf,
    NumPy scalars, complex numbers, nested tuples, lists and dicts keep their types."""
    student = kernel(_define("def echo(*args, **kwargs):\n    return args, kwargs\n"), "echo")
    values = (np.sin(np.arange(12.0)).reshape(3, 4), np.array([np.nan, np.inf, -0.0, 5e-324]), np.arange(6, dtype=np.int32).reshape(2, 3),
              np.array([True, False]), np.exp(1j * np.arange(3.0)) / 3, np.float32(1.5), np.int64(7),
              2.5, 3, True, None, "text", 1 + 2j, [1, (2.0, [3])], {"a": np.eye(2), 4: "four"}, np.empty((0, 3)))
    args, kwargs = student(*values, option=np.float64(np.pi))
    assert len(args) == len(values)
    for sent, got in zip(values, args):
        assert type(got) is type(sent), (sent, got)
        if isinstance(sent, np.ndarray):
            assert got.dtype == sent.dtype and got.shape == sent.shape and got.tobytes() == sent.tobytes()
    assert args[13] == [1, (2.0, [3])] and args[14]["a"].tolist() == [[1, 0], [0, 1]] and args[14][4] == "four"
    assert type(kwargs["option"]) is np.float64 and kwargs["option"] == np.pi


@random_draws(false_fail=0.0, why="an identity: the same draws from the same state, in the kernel and here")
def test_what_the_call_writes_into_its_arguments_comes_back(kernel, seed):
    """A dict argument gets what the function stored, and a generator argument ends in the state the
    same draws leave it in locally."""
    source = ("def step(x, rng, info):\n"
              "    draws = rng.standard_normal(5)\n"
              "    info['ess'] = 3.5\n"
              "    info['parents'] = rng.integers(0, 4, size=4)\n"
              "    return x + draws.sum()\n")
    student = kernel(_define(source), "step")
    local = _define(source)["step"]
    remote_rng, local_rng = np.random.default_rng(seed), np.random.default_rng(seed)
    remote_info, local_info = {}, {}
    assert student(1.0, remote_rng, info=remote_info) == local(1.0, local_rng, info=local_info)
    assert remote_rng.bit_generator.state == local_rng.bit_generator.state
    assert remote_info["ess"] == 3.5 and remote_info["parents"].tolist() == local_info["parents"].tolist()


BAND_CASE = (np.linspace(0, 10, 21), np.sin(np.linspace(0, 10, 21)), np.sin(np.linspace(0, 10, 21)) + 0.01,
             0.1 + 0.01 * np.linspace(0, 10, 21))
"""t, truth, mean and std of a plot blank's case."""


def _drawn(kernel, source: str):
    """A new Axes, and what the kernel's ``plot`` defined by ``source`` returned when it drew BAND_CASE on it."""
    ax = Figure().subplots()
    return ax, kernel(_define(source), "plot")(ax, *BAND_CASE)


def test_a_plot_blank_draws_on_the_axes_the_check_gave_it(kernel):
    """The Axes the check passes is drawn on with the same lines, band, labels and legend, and is the
    object returned, so the plot checks inspect it as they would locally."""
    source = ("def plot(ax, t, truth, mean, std):\n"
              "    ax.plot(t, truth, label='truth')\n"
              "    ax.plot(t, mean, label='estimate')\n"
              "    ax.fill_between(t, mean - 3 * std, mean + 3 * std, alpha=0.3, label='3 sigma')\n"
              "    ax.set(xlabel='Time [s]', ylabel='c [m2/kg]', title='c')\n"
              "    ax.legend()\n"
              "    return ax\n")
    t, truth, mean, std = BAND_CASE
    ax, returned = _drawn(kernel, source)
    assert returned is ax
    check_band_plot(ax, returned, t, truth, mean, std, "plot")
    assert ax.get_xlabel() == "Time [s]" and [x.get_text() for x in ax.get_legend().get_texts()] == ["truth", "estimate", "3 sigma"]
    local = Figure().subplots()
    _define(source)["plot"](local, t, truth, mean, std)
    assert diagnosis._same(diagnosis._leaves(ax), diagnosis._leaves(local)), "the diagnosis sees the plot as drawn"


def test_a_legend_made_from_handles_and_labels_crosses_with_its_entries(kernel):
    """Fairness review: a correct plot that labels its legend with ax.legend(handles, labels), on unlabelled
    artists, lost its points: the grader's copy of the Axes called ax.legend() alone, which found no
    labelled artist (and warned)."""
    source = ("def plot(ax, t, truth, mean, std):\n"
              "    truth_line, = ax.plot(t, truth)\n"
              "    mean_line, = ax.plot(t, mean)\n"
              "    band = ax.fill_between(t, mean + 3 * std, mean - 3 * std, alpha=0.3)\n"
              "    ax.set(xlabel='t, sec', ylabel='c in m$^2$/kg', title='c')\n"
              "    ax.legend([truth_line, mean_line, band], ['truth', 'estimate', '99.7% region'])\n"
              "    return ax\n")
    t, truth, mean, std = BAND_CASE
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ax, returned = _drawn(kernel, source)
    check_band_plot(ax, returned, t, truth, mean, std, "plot")
    assert [x.get_text() for x in ax.get_legend().get_texts()] == ["truth", "estimate", "99.7% region"]


def test_course_objects_and_callbacks_cross(kernel):
    """A course dataclass comes back as itself; a function the check passes in is called back in the
    grader's process, however often the student's function calls it."""
    calls = []

    def model(x):
        calls.append(x.shape)
        return 2.0 * x

    source = ("def run(f, points):\n"
              "    out = np.stack([f(p) for p in points])\n"
              "    return FilterHistory(*(out[:, k % 4] for k in range(10)))\n")
    student = kernel(_define(source, FilterHistory=FilterHistory), "run")
    points = np.arange(12.0).reshape(3, 4)
    history = student(model, points)
    assert isinstance(history, FilterHistory) and len(calls) == 3
    assert np.array_equal(history.mean, 2.0 * points[:, 0])


def test_the_grader_answers_only_for_earlier_blanks_and_never_for_the_one_under_test(kernel):
    """Isolation: the student's run calls the reference's step for a blank graded earlier, its own
    for a blank graded later, and its own run when it calls itself."""
    reference = type(np)("reference")
    exec("def step(x):\n    return x + 100.0\ndef later(x):\n    return x + 1000.0\n"
         "def run(x, depth=0):\n    return step(x) + later(x)\n", reference.__dict__)  # the reference's run calls both
    source = ("def step(x):\n    return x + 1.0\n"
              "def later(x):\n    return x + 10.0\n"
              "def run(x, depth=0):\n    return step(x) + later(x) + (run(x, 1) if depth == 0 else 0.0)\n")
    namespace = _define(source)
    student = kernel(namespace, "run", earlier=frozenset({"step", "run"}))
    isolated = isolate(student, reference, ("step", "later", "run"))
    # step from the reference (earlier), later from the student (graded later); the recursive call
    # is the notebook's own run, which sees the notebook's own step, as in a local isolate
    assert isolated(0.0) == (100.0 + 10.0) + (1.0 + 10.0)
    assert namespace["step"](0.0) == 1.0  # the notebook's own names are left alone


@random_draws(false_fail=0.0, why="an identity: the served step is the reference's, on the generator state the run reached")
def test_a_served_blank_answers_only_the_calls_the_reference_makes_and_a_few_of_their_form(kernel, seed):
    """The served reference is no oracle: it answers a call of the student's run if the reference's own
    run makes that call on the same arguments (to rounding), as often as it makes it; else, if it has
    the form of one of those calls (parameters, shapes, kinds of number), at most as many times as the
    reference's run calls it, plus WINDOW; every other call is answered by the student's own step in the
    kernel. So an honest run is isolated from a wrong step of its own, and a run that asks the served
    step about inputs of its choosing gets a bounded number of answers, of the reference's form only."""
    reference = type(np)("reference")
    exec("def step(x, rng):\n    return x + 100.0 + rng.standard_normal()\n"
         "def run(x, rng):\n    return [step(x, rng), step(2.0 * x, rng)]\n", reference.__dict__)
    honest = ("def step(x, rng):\n    return x - 5.0\n"  # a wrong step of the student's own
              "def run(x, rng):\n    return [step(x, rng), step(x + x * (1 + 1e-12), rng)]\n")
    student = isolate(kernel(_define(honest), "run", earlier=frozenset({"step"})), reference, ("step", "run"))
    want = reference.run(np.array([1.0, 2.0]), np.random.default_rng(seed))
    got = student(np.array([1.0, 2.0]), np.random.default_rng(seed))
    assert np.allclose(got[0], want[0]) and np.allclose(got[1], want[1])  # both calls served, to rounding
    harvest = ("def step(x, rng):\n    return -1.0\n"
               "def run(x, rng):\n"
               "    return [step(np.ones(5, dtype=int), rng)] + [float(np.ravel(step(x + k, rng))[0]) for k in range(40)]\n")
    student = isolate(kernel(_define(harvest), "run", earlier=frozenset({"step"})), reference, ("step", "run"))
    other_form, *same_form = student(np.array([1.0]), np.random.default_rng(seed))
    assert other_form == -1.0, "a call of another form than the reference's is answered by the student's own step"
    served = [value for value in same_form if value != -1.0]
    # x + 0 and x + 1 (= 2 x) are the reference's own two calls; then its budget of numbers: twice the
    # two its calls held (x, one number each), plus WINDOW times its largest call's (one)
    assert len(served) == 2 + 2 * 2 + served_calls.WINDOW and same_form[len(served):] == [-1.0] * (40 - len(served))


def test_a_served_call_is_the_same_call_by_position_or_by_keyword(kernel):
    """The reference's run passes u by keyword and leaves the default out; a student's run that passes
    u by position, or spells the default out, makes the same call, and the grader serves it (a fairness
    review found castaway-bob's run_rank4 charged for a wrong kalman_step when it passed u by position)."""
    reference = type(np)("reference")
    exec("def step(x, u=None, scale=1.0):\n    return x + 100.0 * scale + (0.0 if u is None else u)\n"
         "def run(x):\n    return [step(x, u=1.0), step(x)]\n", reference.__dict__)
    source = ("def step(x, u=None, scale=1.0):\n    return -1.0\n"  # a wrong step of the student's own
              "def run(x):\n    return [step(x, 1.0), step(x, None, 1.0)]\n")
    student = isolate(kernel(_define(source), "run", earlier=frozenset({"step"})), reference, ("step", "run"))
    assert student(np.array([1.0])) == [101.0 + 1.0, 101.0]


def test_a_served_call_is_the_same_call_whatever_its_info_dict_held(kernel):
    """A dict argument is where the call writes what it reports: a run that hands the served step a
    fresh dict (or one its previous step filled) makes the reference's call (a fairness review found
    reentry-pf's run_particle_filter graded with the student's own pf_step because of it)."""
    reference = type(np)("reference")
    reference.np = np
    exec("def step(x, info=None):\n    info['calls'] = info.get('calls', 0) + 1\n    return x + 100.0\n"
         "def run(x):\n    info = {'calls': 0, 'parents': np.arange(3)}\n    return step(step(x, info=info), info=info)\n",
         reference.__dict__)
    source = ("def step(x, info=None):\n    return -1.0\n"  # a wrong step of the student's own
              "def run(x):\n    return step(step(x, info={}), info={'something': 'else'})\n")
    student = isolate(kernel(_define(source), "run", earlier=frozenset({"step"})), reference, ("step", "run"))
    assert student(np.array([1.0])) == 201.0


def test_errors_come_back_by_type_with_the_students_line(kernel):
    """A NumPy or builtin exception is re-raised as itself, another keeps its name; the message says
    which line of the student's function raised it."""
    source = ("class Oops(Exception):\n    pass\n"
              "def solve(A, b, kind):\n"
              "    if kind == 'custom':\n"
              "        raise Oops('my own error')\n"
              "    return np.linalg.solve(A, b)\n")
    student = kernel(_define(source), "solve")
    with pytest.raises(np.linalg.LinAlgError, match="Singular matrix") as caught:
        student(np.zeros((2, 2)), np.ones(2), "solve")
    assert "line 6" in caught.value.where and "np.linalg.solve(A, b)" in caught.value.where
    with pytest.raises(wire.RaisedElsewhere) as caught:
        student(np.eye(2), np.ones(2), "custom")
    assert type(caught.value).__name__ == "Oops" and str(caught.value) == "my own error"


def test_warnings_fail_with_a_message_or_reach_the_check_that_asked_for_them(kernel):
    source = "def log(x):\n    print('computing')\n    return np.log(x)\n"
    reference = type(np)("reference")
    student = kernel(_define(source), "log")
    with pytest.raises(AssertionError, match="log gave the warning RuntimeWarning"):
        isolate(student, reference, ("log",))(np.array([-1.0]))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        value = isolate(student, reference, ("log",), warnings_fail=False)(np.array([-1.0]))
    assert np.isnan(value[0]) and [w.category for w in caught] == [RuntimeWarning]


def test_a_plot_drawn_with_pyplot_is_told_to_draw_on_its_axes_not_to_look_for_a_negative_log(kernel):
    """A student's plot that draws with plt.plot leaves the graded Axes without labelled artists, and its
    legend warns: the message said to look for "a log or square root of a negative number" (fairness
    review of reentry-srekf)."""
    source = ("def draw(ax, t):\n    import matplotlib.pyplot as plt\n    plt.plot(t, t, label='truth')\n"
              "    ax.legend()\n    return ax\n")
    from matplotlib.figure import Figure

    student = kernel(_define(source), "draw")
    with pytest.raises(AssertionError) as failed:
        isolate(student, type(np)("reference"), ("draw",))(Figure().subplots(), np.arange(3.0))
    message = str(failed.value)
    assert "No artists with labels" in message and "draw with ax.plot" in message and "negative" not in message, message


def test_an_object_the_wire_cannot_carry_is_a_clear_failure(kernel):
    """The eq-dunder trick (an object that equals anything) never reaches a comparison."""
    source = ("class Anything:\n    def __eq__(self, other):\n        return True\n"
              "def gain(B, H, R):\n    return Anything()\n")
    student = kernel(_define(source), "gain")
    with pytest.raises(TypeError, match="gain returned a Anything object, which the grader cannot compare"):
        student(np.eye(2), np.eye(2), np.eye(2))


def test_a_missing_function_is_named(kernel):
    k = kernel({"kupdate": 3}, "kupdate")
    assert k.peer is None and "kupdate is a int, not a function" in k.why_not
    k = kernel({}, "predict")
    assert k.peer is None and "predict is not defined" in k.why_not


@pytest.fixture
def pair():
    """(the grader's end, the kernel's end) of a connected socket pair, closed afterwards."""
    ends = socket.socketpair()
    yield ends
    for end in ends:
        end.close()


def _crafted(header: dict, buffers: list[bytes] = ()) -> bytes:
    data = json.dumps(header).encode()
    out = struct.pack("!QQ", len(data), len(buffers)) + data
    for b in buffers:
        out += struct.pack("!Q", len(b)) + b
    return out


@pytest.mark.parametrize("header, buffers, match", [
    ({"op": "return", "value": {"t": "array", "dtype": "|O", "shape": [1], "buffer": 0}}, [b"\0" * 8], "array of object"),
    ({"op": "return", "value": {"t": "array", "dtype": "<f8", "shape": [3], "buffer": 0}}, [b"\0" * 16], "size does not match"),
    ({"op": "return", "value": {"t": "array", "dtype": "<f8", "shape": [1], "buffer": 5}}, [b"\0" * 8], "buffer that is not there"),
    ({"op": "return", "value": {"t": "pickle", "v": "gASVAAAAAAAAAAB9lC4="}}, [], "unknown kind"),
    ({"op": "return", "value": {"t": "dataclass", "module": "os", "name": "stat_result", "fields": {}}}, [], "dataclass from os"),
    ({"op": "return", "value": {"t": "generator", "bit_generator": "Evil", "state": {}}}, [], "bit generator"),
    ({"op": "return", "value": {"t": "py", "v": [1, 2]}}, [], "not plain"),
    ({"op": "launch"}, [], "unexpected message"),
])
def test_a_hostile_kernels_messages_are_refused(header, buffers, match, pair):
    """Whatever a tampered kernel sends, the grader decodes only data, or raises ProtocolError."""
    grader, kernel_end = pair
    kernel_end.sendall(_crafted(header, list(buffers)))
    peer = Peer(Wire(grader))
    with pytest.raises(ProtocolError, match=match):
        peer.apply_answer(*peer.serve_until_answer(), (), {})


def test_an_oversized_message_is_refused_before_it_is_read(pair):
    grader, kernel_end = pair
    kernel_end.sendall(struct.pack("!QQ", wire.MAX_MESSAGE_BYTES + 1, 0))
    with pytest.raises(ProtocolError, match="larger than the wire allows"):
        Wire(grader).receive()


def test_a_silent_kernel_times_out(pair):
    receiving = Wire(pair[0])
    receiving.deadline = time.monotonic() + 0.2
    with pytest.raises(wire.PeerTimeout):
        receiving.receive()


def test_the_hidden_block_has_one_form():
    code = "from solutions.train_kf.hidden_tests import check_kupdate\ncheck_kupdate(kupdate)\n"
    assert hidden_blocks.hidden_test(code) == HiddenTest("solutions.train_kf.hidden_tests", "check_kupdate", "kupdate")
    for bad in ("from solutions.train_kf.hidden_tests import check_kupdate\ncheck_kupdate(predict)\n",
                "from solutions.train_kf.reference import kupdate\nkupdate(1)\n",
                "import os\nfrom solutions.train_kf.hidden_tests import check_kupdate\ncheck_kupdate(kupdate)\n",
                "from solutions.train_kf.hidden_tests import check_kupdate\ncheck_kupdate(kupdate, seed=1)\n",
                "from solutions.train_kf.hidden_tests import check_kupdate as c\nc(kupdate)\n",
                "from .solutions.train_kf.hidden_tests import check_kupdate\ncheck_kupdate(kupdate)\n",
                "from solutions.train_kf.hidden_tests import check_kupdate, predict\ncheck_kupdate(kupdate)\n",
                "from solutions.train_kf.hidden_tests import check_kupdate\nresult = check_kupdate(kupdate)\n",
                "from solutions.train_kf.hidden_tests import check_kupdate\ncheck_kupdate(*kupdate)\n",
                "from solutions.train_kf.hidden_tests import check_kupdate\ncheck_kupdate(kupdate.x)\n",
                "from solutions.train_kf.hidden_tests import check_kupdate\ncheck_kupdate(kupdate)\ncheck_kupdate(kupdate)\n",
                "from solutions.Train.hidden_tests import check_kupdate\ncheck_kupdate(kupdate)\n",
                "check_kupdate(kupdate)\n", ""):
        with pytest.raises(HiddenTestFormError):
            hidden_blocks.hidden_test(bad)
    source = "validate(kupdate)\n### BEGIN HIDDEN TESTS\n" + code + "### END HIDDEN TESTS\n"
    assert hidden_blocks.split(source) == ("validate(kupdate)\n", "\n" + code)


def test_a_missing_reference_stops_grading_before_any_kernel(monkeypatch):
    test = HiddenTest("solutions.no_such_lab.hidden_tests", "check_f", "f")
    with pytest.raises(hidden_blocks.ReferenceUnavailable, match="cannot import solutions.no_such_lab.hidden_tests"):
        test.load()


def test_the_codec_never_sends_code():
    """Functions travel as numbers the other side calls back, never as code."""
    buffers: list[bytes] = []
    node = Codec().encode((np.sin, lambda x: x), buffers)
    assert [item["t"] for item in node["items"]] == ["callable", "callable"] and buffers == []


@random_draws(false_fail=0.0, why="the failures are the grader's verdicts on what the call did, whatever it drew")
def test_a_call_that_writes_into_an_array_argument_or_uses_the_global_generator_fails_by_name(kernel, seed):
    """Fairness reviews of issue 30: kupdate's x_f += ... and pf_step's np.random.choice kept their marks. The
    kernel reports both with the call's return, and the call fails with a message that names the argument."""
    writes = kernel(_define("def kupdate(x_f, B_f):\n    x_f += 1.0\n    return x_f, B_f\n"), "kupdate")
    with pytest.raises(AssertionError, match=r"kupdate changed its argument x_f in place.*x_f = x_f \+ \.\.\."):
        writes(np.zeros(2), np.eye(2))
    keyword = kernel(_define("def sort_it(w):\n    w.sort()\n    return w\n"), "sort_it")
    with pytest.raises(AssertionError, match="its argument w in place"):
        keyword(w=np.array([3.0, 1.0]))
    own = kernel(_define("def own(x):\n    y = x.copy()\n    y += 1.0\n    y /= 2.0\n    return y\n"), "own")
    assert own(np.zeros(2)).tolist() == [0.5, 0.5]
    source = "def draw(n, rng):\n    return np.random.standard_normal(n)\n"
    with pytest.raises(AssertionError, match="global generator .* not from the rng it was given"):
        kernel(_define(source), "draw")(3, np.random.default_rng(seed))
    assert kernel(_define(source), "draw")(3, None).shape == (3,), "no rng given: the global generator is no mistake"


def test_text_that_no_file_can_store_crosses_as_a_replacement_character(kernel):
    """Adversarial review of issue 31: a lone surrogate printed or raised by the student's function during a
    hidden test reached the graded notebook, which nbgrader then could not write: the submission went ungraded."""
    student = kernel(_define("def f(x):\n    print('debug', chr(0xD800))\n    return 'a' + chr(0xDC00) + '\\U0001F600'\n"), "f")
    import contextlib
    import io
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        value = student(1.0)
    assert value == "a\ufffd\U0001F600" and printed.getvalue() == "debug \ufffd\n"
    printed.getvalue().encode("utf-8")
    raises = kernel(_define("def g(x):\n    raise ValueError('bad ' + chr(0xD800))\n"), "g")
    with pytest.raises(ValueError, match="bad \ufffd"):
        raises(1.0)


def test_a_title_set_on_the_left_is_a_title(kernel):
    """Fairness review of issue 30: ax.set_title(..., loc="left") lost the plot's marks, as only the centred title was read."""
    ax, returned = _drawn(kernel, "def plot(ax, t, truth, mean, std):\n"
                                  "    ax.fill_between(t, mean - 3 * std, mean + 3 * std, label='3 sigma')\n"
                                  "    ax.plot(t, truth, label='truth')\n    ax.plot(t, mean, label='estimate')\n"
                                  "    ax.set(xlabel='Time [s]', ylabel='c [m2/kg]')\n    ax.set_title('c', loc='left')\n"
                                  "    ax.legend()\n    return ax\n")
    check_band_plot(ax, returned, *BAND_CASE, "plot")


@random_draws(false_fail=0.0, why="an identity: the same children from the same seed sequence and count")
def test_a_generator_spawns_the_same_children_for_the_same_state_and_new_ones_on_the_next_call(kernel, seed):
    """A final review of issue 30: rng.spawn in the kernel gave other children on every call, since the generator
    was rebuilt there without its seed sequence, and an honest step that spawned lost its marks; the review after it:
    a spawning step gave the same children on every call of a filter's loop, and the kernel learned the seed. The
    kernel's children are not the ones this process would spawn (its entropy is a digest), but they are the same
    for the same generator, and new ones each call."""
    student = kernel(_define("def draw(rng):\n    return rng.spawn(1)[0].random(3), rng.bit_generator.seed_seq.entropy\n"), "draw")
    given = np.random.default_rng([seed, 4])
    (first, entropy), (second, _) = student(given), student(given)
    assert student(np.random.default_rng([seed, 4]))[0].tolist() == first.tolist() != second.tolist(), (
        "the same state gives the same child, and the next call a new one, as with the student's own generator")
    assert wire._children_spawned(given.bit_generator.seed_seq) == 2
    assert seed not in np.atleast_1d(entropy).tolist(), "the kernel never learns the seed: a one-way digest stands in"


@pytest.mark.parametrize("lab_id, blank", [("reentry-pf", "pf_step"), ("nonlinear-filters", "bootstrap_pf_step")])
@random_draws(false_fail=0.0, why="every correct step passes its hidden check on every submission seed (test_alternatives)")
def test_every_correct_random_step_passes_its_hidden_check_across_the_wire(kernel, lab_id, blank, seed):
    """A review of issue 30: the steps that spawn children of rng were graded in this process only (test_alternatives)
    or not at all through `grade` (test_alternatives_graded grades the first three of each blank), while spawn counting
    happens on the wire. Every alternative and the model answer, in a kernel, through the whole hidden check."""
    from autograder.catalogues.alternatives import catalogue as alternatives
    from autograder.hidden_tests import cases
    from autograder.labs import get_lab

    lab = get_lab(lab_id)
    model = cells.model_answers(cells.read(lab.source_notebook))[blank]
    blanks = lab.blanks()
    check = getattr(lab.hidden_module("hidden_tests"), f"check_{blank}")
    for code in [model, *(a.code for a in alternatives(lab) if a.blank == blank)]:
        namespace = dict(vars(lab.reference()))
        exec(compile(code, f"<answer {blank}>", "exec"), namespace)
        with cases.seeded(seed):
            check(kernel(namespace, blank, frozenset(blanks[: blanks.index(blank)])))


def test_a_generator_whose_state_cannot_cross_is_refused_and_the_kernel_goes_on(kernel):
    """A review of issue 30: an MT19937, Philox or SFC64 generator returned from the kernel ended its connection (their
    state holds arrays, which JSON does not take), and the student was told that their own code had ended it."""
    student = kernel(_define("def make(kind):\n    return np.random.Generator(getattr(np.random, kind)(1))\n"), "make")
    for kind in ("MT19937", "Philox", "SFC64"):
        with pytest.raises(Exception) as raised:
            student(kind)
        assert f"a random generator with bit generator {kind}" in str(raised.value), raised.value
    assert isinstance(student("PCG64"), np.random.Generator)

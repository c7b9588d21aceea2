"""Attacks on grading that autograder/catalogues/cheats.py does not list, graded as nbgrader grades them.

A student who has read the kit's source (course/ and autograder/) tries to earn marks they did not,
or to break grading for others: through the blanks the grader serves, the socket to the grader,
the grader's memory and time, the size of what a cell outputs, the kernel's messages, processes
and shared memory that outlive the kernel, core dumps, HTML for whoever views the graded notebook,
and symbolic links or huge files in the submissions. Each graded run is a solved train-kf notebook
with several attacks planted, run through the grading execute step with the course's configuration
(the sandboxed kernel, hidden tests in the grader's process), each in a fresh process whose peak
memory is measured, three runs two at a time; the launcher's own defences are tried on the
launcher alone. README (What grading defends against) lists what each defence does.
"""

from __future__ import annotations

import copy
import ctypes
import errno
import json
import multiprocessing
import os
import resource
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import landlockpy
import pyseccomp
import nbformat
import pytest
from nbconvert.exporters import HTMLExporter
from nbformat import NotebookNode
from nbgrader.server_extensions.formgrader import handlers as formgrader_handlers
from traitlets.config import Config

import solutions.train_kf.reference as reference
from autograder import cells
from autograder.pipeline import confined_check, intake, nbgrader_apps
from autograder.kernel import sandbox
from autograder.catalogues import submissions
from autograder.pipeline.output_caps import MAX_MESSAGE_CHARS, error_output
from autograder.pipeline.execute import GradingExecute
from autograder.hidden_tests.isolate import called_blanks
from solutions.train_kf import hidden_tests as train_kf
from autograder.pipeline.inert_html import InertHtml
from autograder.kernel.wire import PeerTimeout
from autograder.labs import get_lab
from autograder.catalogues.mistakes import catalogue
from autograder.pipeline.restore import grader_notes
from defended_runs import graded_run, sanitized
from test_defences import scores, trimmed

TRAIN = get_lab("train-kf")
MAX_OUTPUT = 1_000_000
"""The course's cap on each cell's output (nbgrader_config.py)."""
GRADER_MEMORY = 500 * 2**20
"""The most memory a grading process may hold at its peak in these runs (it holds about 270 MiB)."""
SAFETY_MARGIN = 3 * 2**30
"""How much a grading process here may grow before Python refuses it memory: without the defences,
an attack would otherwise take the test machine's memory."""

PEER = 'peer = __import__("sys")._getframe(1).f_locals["self"]  # the kernel side of the socket, from the stack'


def _stub(blank: str, params: str, body: str) -> str:
    return f"def {blank}({params}):\n" + "".join(f"    {line}\n" for line in body.strip("\n").splitlines())


WIRE = {
    # the served-blank attack: the student's own information form is wrong, and the covariance
    # form returns it; the grader used to answer the call with the reference's information form
    "gain_covariance_form": _stub("gain_covariance_form", "B, H, R", "return gain_information_form(B, H, R)"),
    # a forged answer whose JSON header is nested 100,000 deep
    "process_noise": _stub("process_noise", "sigma, dt_min=1.0", f"""
{PEER}
data = b'{{"op": "return", "value": ' + b'{{"t": "list", "items": [' * 100_000 + b']}}' * 100_000 + b'}}'
peer.wire.sock.sendall(__import__("struct").pack("!QQ", len(data), 0) + data)
"""),
    # a correct predict that prints 3,000,000 characters in each call of the hidden test
    "predict": _stub("predict", "x, B, A, Q", """
print("x" * 3_000_000)
return A @ x, A @ B @ A.T + Q
"""),
    # an exception whose message is 3,000,000 characters long
    "kupdate": _stub("kupdate", "x_f, B_f, y, H, R", 'raise ValueError("y" * 3_000_000)'),
    # a forged answer of 600 arrays that all point at one buffer of 1 MiB: 600 MiB once decoded (once:
    # the grader's diagnosis calls nees again after the test fails)
    "nees": "_forged = []\n\n\n" + _stub("nees", "errors, covariances", f"""
if _forged:
    return errors[:, 0]
_forged.append(1)
{PEER}
node = {{"t": "array", "dtype": "<f8", "shape": [131072], "buffer": 0}}
peer.wire.send({{"op": "return", "value": {{"t": "list", "items": [node] * 600}}, "written": {{}}}}, [bytes(1 << 20)])
"""),
}
"""train-kf answers that attack over the wire, by blank."""

PROCESSES = '''import ctypes, os, signal, time
from IPython.display import HTML, display

libc = ctypes.CDLL(None, use_errno=True)
found = {}
def attempt(name, action):
    try:
        action()
        found[name] = "ok"
    except OSError as error:
        found[name] = type(error).__name__
def trace():
    if libc.ptrace(16, os.getppid(), None, None) != 0:  # PTRACE_ATTACH
        raise OSError(ctypes.get_errno(), "ptrace")
attempt("signal the kernel's parent", lambda: os.kill(os.getppid(), 0))
attempt("trace the kernel's parent", trace)
attempt("read the parent's memory", lambda: open(f"/proc/{os.getppid()}/mem", "rb").read(1))
attempt("list the processes", lambda: os.listdir("/proc"))
attempt("write in /dev/shm", lambda: open("/dev/shm/kit-attack", "w").close())
attempt("connect to an abstract socket", lambda: __import__("socket").socket(1).connect("\\0NAME"))
print(found)
# a daemon: it leaves the kernel's process group and session, and ignores the signals of a shutdown
if os.fork() == 0:
    os.setsid()
    if os.fork() == 0:
        libc.prctl(15, b"NAME", 0, 0, 0)
        for sig in (signal.SIGTERM, signal.SIGHUP, signal.SIGINT):
            signal.signal(sig, signal.SIG_IGN)
        time.sleep(600)
    os._exit(0)
os.wait()
# System V shared memory: a segment stays, memory and all, after its process ends, unless removed
libc.shmget(KEY, 1 << 20, 0o1000 | 0o600)  # IPC_CREAT
# scripts, for whoever views the graded notebook
from IPython.display import Javascript, Markdown
display(HTML("<script>alert('html')</script>"), Javascript("alert('js')"), Markdown("<img src=x onerror=alert('md')>"))
# displayed data, not printed text: 10 MB of it
for _ in range(50):
    display(HTML("<p>" + "z" * 200_000 + "</p>"))
'''
"""A cell added at the end: the kernel's reach over other processes, a daemon, shared memory that
would outlive it, and a display flood."""
LOUD_CELLS = 15
"""Cells added after it, each printing 900,000 characters, under the cell's cap but not the notebook's."""

SERVED = {
    # an exception whose message cannot be made: str() of it raises
    "kupdate": "class _Unspeakable(Exception):\n    def __str__(self):\n        raise RuntimeError('no words')\n\n\n"
               + _stub("kupdate", "x_f, B_f, y, H, R", "raise _Unspeakable()"),
    # a gigantic answer: 100 MB, within what the wire carries
    "gain_information_form": _stub("gain_information_form", "B, H, R", "return np.zeros(12_500_000)"),
    # answers the kernel's side cannot send: a list that holds itself, and an integer of 5,000 digits
    "predict": _stub("predict", "x, B, A, Q", "loop = []\nloop.append(loop)\nreturn loop"),
    "process_noise": _stub("process_noise", "sigma, dt_min=1.0", "return 10**5000"),
    # the grader's code in the kernel replaced: for two tests, the first message (which the grader
    # reads in its own process) is nested 30,000 deep, or 300 MB long
    "gain_covariance_form": _stub("gain_covariance_form", "B, H, R", "return gain_information_form(B, H, R)") + """

def _first_message(path, name, serve=__import__("sys").modules["_kit_grading"].serve):
    import socket, struct
    if name not in ("gain_covariance_form", "nees"):
        return serve(path, name)
    if name == "gain_covariance_form":
        data = b'{"op": "ready", "pad": ' + b"[" * 30_000 + b"]" * 30_000 + b"}"
    else:
        data = b'{"op": "ready", "pad": "' + b"x" * 300_000_000 + b'"}'
    connection = socket.socket(socket.AF_UNIX)
    connection.connect(path)
    connection.sendall(struct.pack("!QQ", len(data), 0) + data)


__import__("sys").modules["_kit_grading"].serve = _first_message
""",
}
"""train-kf answers for the run on the reference's cost, by blank."""

BIG_CALL = ('''    if not _calls:  # the notebook's own list, which the copy of run_filter that the grader calls shares
        _calls.append(1)
        m = 5000
        kupdate(np.zeros(1), np.eye(1), np.zeros(m), np.ones((m, 1)), 1.0)
''', "    T, n = y.shape[0], x0.shape[0]\n")
"""Lines put into run_filter before its first line of code: once per notebook, it calls the served
kupdate with H of shape (5000, 1), a message of 80 kB that makes the reference build and solve a
5000 x 5000 system, 600 MB and seconds of work."""


MESSAGES = [
    # widgets' messages of the kernel's own making: 10 MB of state, then a widget without its module
    "from ipykernel.comm import Comm\nfor _ in range(10):\n    Comm(target_name='jupyter.widget', data={'state': {"
    "'_model_name': 'X', '_model_module': 'x', '_model_module_version': '1', 'v': 'v' * 1_000_000}})",
    "Comm(target_name='jupyter.widget', data={'state': {'_model_name': 'OutputModel'}})",
    # a message of 150 MB on standard output
    "import sys\nsys.stdout.write('x' * 150_000_000)\nsys.stdout.flush()",
    "print('graded on')",
]
"""Cells for the run on the kernel's messages (a notebook of its own, no lab)."""
MESSAGE_CAP = 16 * 2**20
"""The cap on a kernel's message in that run (the course's is 128 MiB)."""


def _answer(nb: NotebookNode, blank: str) -> NotebookNode:
    [cell] = [c for c in nb.cells if cells.is_code_answer(c) and cells.grade_id(c) == blank]
    return cell


def _planted(blank: str, slug: str, nb: NotebookNode) -> None:
    """Plant the catalogued mistake ``slug`` of ``blank`` in ``nb``."""
    [mistake] = [m for m in catalogue(TRAIN) if m.blank == blank and m.slug == slug]
    cell = _answer(nb, blank)
    cell.source = mistake.apply(cell.source)


def wire_notebook(leftover: tuple[str, int]) -> NotebookNode:
    """The wire run's notebook; ``leftover`` names its daemon and its shared memory segment's key."""
    nb = copy.deepcopy(submissions.solved(TRAIN))
    _planted("gain_information_form", "B-not-inverted", nb)
    for blank, source in WIRE.items():
        _answer(nb, blank).source = source
    daemon, key = leftover
    nb.cells.append(nbformat.v4.new_code_cell(PROCESSES.replace("NAME", daemon).replace("KEY", str(key))))
    nb.cells += [nbformat.v4.new_code_cell('print("w" * 900_000)') for _ in range(LOUD_CELLS)]
    return nb


def served_notebook() -> NotebookNode:
    nb = copy.deepcopy(submissions.solved(TRAIN))
    for blank, source in SERVED.items():
        _answer(nb, blank).source = source
    cell = _answer(nb, "run_filter")
    lines, first = BIG_CALL
    assert first in cell.source
    cell.source = "_calls = []\n\n\n" + cell.source.replace(first, lines + first)
    return nb


def graded_in_own_process(nb_json: str, course: str) -> tuple[str, int]:
    """``nb_json`` after the execute step, and this process's peak memory in bytes (it runs in a
    process of its own)."""
    size = int(open("/proc/self/statm").read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
    resource.setrlimit(resource.RLIMIT_AS, (size + SAFETY_MARGIN, resource.getrlimit(resource.RLIMIT_AS)[1]))
    graded = graded_run(nb_json, TRAIN.id, course)
    return graded, own_peak_memory()


def own_peak_memory() -> int:
    """This process's own peak resident memory in bytes (VmHWM). Not getrusage's ru_maxrss: Linux
    keeps that across execve, so a spawned process reports its parent's peak at the fork (a pytest
    worker grown to 2.6 GiB by the test files it ran before this one)."""
    [line] = [line for line in Path("/proc/self/status").read_text().splitlines() if line.startswith("VmHWM:")]
    return int(line.split()[1]) * 1024


def daemons(name: str) -> list[int]:
    """The processes named ``name`` on this machine."""
    found = []
    for entry in os.scandir("/proc"):
        try:
            if entry.name.isdigit() and Path(entry.path, "comm").read_text().strip() == name:
                found.append(int(entry.name))
        except OSError:
            continue
    return found


def segments(key: int) -> list[int]:
    """The ids of this machine's System V shared memory segments with ``key``."""
    rows = [line.split() for line in Path("/proc/sysvipc/shm").read_text().splitlines()[1:]]
    return [int(row[1]) for row in rows if int(row[0]) == key]


@pytest.fixture(scope="module")
def leftover():
    """A name for the wire run's daemon (and for an abstract Unix socket that listens meanwhile)
    and a key for its shared memory segment; any process of that name is killed, and any segment
    with that key removed, afterwards."""
    token = secrets.token_hex(4)
    name, key = f"kit-{token}", int(token, 16) & 0x7FFFFFFF
    with socket.socket(socket.AF_UNIX) as listening:
        listening.bind(f"\0{name}")
        listening.listen(1)
        yield name, key
    for pid in daemons(name):
        os.kill(pid, signal.SIGKILL)
    for shmid in segments(key):
        ctypes.CDLL(None).shmctl(shmid, 0, None)  # IPC_RMID


def executed_in_own_process(sources: list[str], folder: str, max_message_bytes: int) -> tuple[str, int]:
    """``sources`` as code cells run by the grading executor with the course's configuration (no
    gradebook, cells stopped after 5 s), in ``folder``, its kernel's messages capped at
    ``max_message_bytes``: the executed notebook, and this process's peak memory in bytes."""
    os.environ["GRADING_CELL_TIMEOUT"] = "5"
    config = nbgrader_apps.course_config(Path(folder))
    config.SandboxedKernelManager.max_message_bytes = max_message_bytes
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(s) for s in sources])
    nb, _ = GradingExecute(config=config).preprocess(nb, {"metadata": {"path": folder}})
    return nbformat.writes(nb), own_peak_memory()


@pytest.fixture(scope="module")
def runs(tmp_path_factory, leftover) -> dict[str, tuple[NotebookNode, int]]:
    """Each attack run, graded once (the kernel's messages only executed): name -> (the graded
    notebook, the grader's peak memory)."""
    course = tmp_path_factory.mktemp("course")
    jobs = {"wire": trimmed(sanitized(wire_notebook(leftover), TRAIN, course), TRAIN),
            "served": trimmed(sanitized(served_notebook(), TRAIN, course), TRAIN)}
    with ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn"), max_tasks_per_child=1) as pool:
        futures = {name: pool.submit(graded_in_own_process, nbformat.writes(nb), str(course))
                   for name, nb in jobs.items()}
        futures["messages"] = pool.submit(executed_in_own_process, MESSAGES, str(tmp_path_factory.mktemp("messages")),
                                          MESSAGE_CAP)
        done = {name: future.result() for name, future in futures.items()}
    return {name: (nbformat.reads(graded, as_version=4), peak) for name, (graded, peak) in done.items()}


def _test_cell(nb: NotebookNode, blank: str) -> NotebookNode:
    [cell] = [c for c in nb.cells if cells.is_autograded_test(c) and cells.grade_id(c) == f"test_{blank}"]
    return cell


def _text(outputs) -> int:
    """How many characters the outputs hold (text, data, error message and traceback)."""
    return sum(len(json.dumps({k: v for k, v in o.items() if k != "output_type"})) for o in outputs)


def test_a_blank_is_served_only_what_its_reference_calls():
    """kupdate's reference calls gain_covariance_form; run_filter's calls predict and kupdate, and
    through kupdate the covariance form; the covariance form calls no other blank, so a student's
    covariance form that calls the information form gets the student's own."""
    blanks = train_kf.BLANKS
    assert called_blanks(reference, "kupdate", blanks) == {"gain_covariance_form"}
    assert called_blanks(reference, "run_filter", blanks) == {"predict", "kupdate", "gain_covariance_form"}
    assert called_blanks(reference, "gain_covariance_form", blanks) == frozenset()


def test_a_blank_that_returns_another_blanks_answer_gets_the_students_own(runs):
    """gain_covariance_form returns gain_information_form(B, H, R), which holds a catalogued
    mistake: before the fix the grader answered that call with the reference, and the blank scored
    full marks for work it did not do."""
    got = scores(runs["wire"][0])
    assert got["test_gain_information_form"] == 0 and got["test_gain_covariance_form"] == 0, got


def test_forged_answers_and_floods_fail_their_own_test_and_the_grader_stays_small(runs):
    """A forged answer that decodes to 600 MiB, and one nested 100,000 deep, fail their blank's
    test and leave the grader's own memory alone (the check runs in a child capped in memory);
    printed text, error messages and displayed data stay within the cell's output cap, and cells
    that each print just under it within the notebook's; the blank that only printed a lot, and
    every untouched blank, keep their marks."""
    nb, peak = runs["wire"]
    assert scores(nb) == {"test_gain_information_form": 0, "test_gain_covariance_form": 0, "test_process_noise": 0,
                          "test_predict": 1.0, "test_kupdate": 0, "test_run_filter": 2.0, "test_nees": 0}
    assert peak < GRADER_MEMORY, f"the grader grew to {peak / 2**20:.0f} MiB"
    predict = _test_cell(nb, "predict").outputs
    assert MAX_OUTPUT < _text(predict) < MAX_OUTPUT + 1000 and "dropped the rest" in predict[-1].text
    [error] = [o for o in _test_cell(nb, "kupdate").outputs if o.output_type == "error"]
    assert error.ename == "ValueError" and len(error.evalue) < MAX_MESSAGE_CHARS + 100
    assert "more characters cut by the grader" in error.evalue
    assert [o.ename for o in _test_cell(nb, "nees").outputs if o.output_type == "error"] == ["AssertionError"]
    assert [o.ename for o in _test_cell(nb, "process_noise").outputs if o.output_type == "error"] == ["GradingError"]
    added = nb.cells[-1 - LOUD_CELLS].outputs
    assert _text(added) < MAX_OUTPUT + 3000 and "dropped the rest" in added[-1].text
    assert 0 < sum(o.output_type == "display_data" for o in added) < 50
    kept = sum(_text(c.outputs) for c in nb.cells if c.cell_type == "code")
    assert 10 * MAX_OUTPUT < kept < 10 * MAX_OUTPUT + 100_000, "the notebook keeps 10,000,000 characters of output"
    assert [_text(c.outputs) for c in nb.cells[-3:]] == [_text([nbformat.v4.new_output("stream", name="stdout", text=(
        "\n[The grader kept the first 0 characters of this cell's output and dropped the rest.]\n"))])] * 3


def test_the_kernel_reaches_no_other_process_and_nothing_it_started_outlives_it(runs, leftover):
    """The kernel cannot signal, trace or read its parent, list processes, write in /dev/shm, or
    reach an abstract Unix socket of the machine's (this test's, which listens); a daemon it started (its own session, shutdown signals ignored) dies with it, and so does a System
    V shared memory segment it made. Before the PID and IPC namespaces both lived on after grading:
    the daemon free to take the machine's CPU and memory from other jobs, the segment holding its
    memory and readable by every later kernel."""
    nb, _ = runs["wire"]
    outputs = nb.cells[-1 - LOUD_CELLS].outputs
    printed = next(o.text for o in outputs if o.output_type == "stream" and o.text.startswith("{"))
    assert eval(printed) == {"signal the kernel's parent": "PermissionError",
                             "trace the kernel's parent": "PermissionError",
                             "read the parent's memory": "PermissionError", "list the processes": "PermissionError",
                             "write in /dev/shm": "PermissionError",
                             "connect to an abstract socket": "ConnectionRefusedError"}
    time.sleep(1)
    name, key = leftover
    assert daemons(name) == [], "a process the kernel started outlived it"
    assert segments(key) == [], "a shared memory segment the kernel made outlived it"


def test_the_references_cost_on_the_students_inputs_stays_out_of_the_grader(runs):
    """run_filter asks the served kupdate for a 5000 x 5000 solve (a message of 80 kB): the child
    that runs the check pays for it, not the grader, and so it does for an answer of 100 MB. A
    kernel whose answer cannot be sent (a list that holds itself, an integer of 5,000 digits, an
    exception that has no message) fails that test. The grader's code in the kernel, replaced,
    sends a first message 300 MB long, which the grader read whole in its own process, or nested
    30,000 deep, which made it raise and end the grading of the submission: both only fail their
    test. The other blanks are graded."""
    nb, peak = runs["served"]
    got = scores(nb)
    assert peak < GRADER_MEMORY, f"the grader grew to {peak / 2**20:.0f} MiB"
    assert {k: v for k, v in got.items() if k != "test_run_filter"} == {
        "test_gain_information_form": 0, "test_gain_covariance_form": 0, "test_process_noise": 0,
        "test_predict": 0, "test_kupdate": 0, "test_nees": 0}
    for blank in ("gain_covariance_form", "nees"):
        [error] = [o for o in _test_cell(nb, blank).outputs if o.output_type == "error"]
        assert "could not reach your function" in error.evalue, error


def test_a_check_that_crashes_or_hangs_stops_alone():
    """The child that runs a check can die or hang without taking the grader with it."""
    crashed, printed, mistake, wrong_on = confined_check.run(lambda: os.kill(os.getpid(), signal.SIGKILL), None, 0)
    assert printed == 0 and mistake is None and wrong_on is None and [o.ename for o in crashed] == ["GradingError"] and "signal 9" in crashed[0].evalue
    with pytest.raises(PeerTimeout):
        confined_check.run(lambda: time.sleep(60), time.monotonic() + 0.5, 0)
    outputs = [error_output("AssertionError", "wrong")]
    assert confined_check.run(lambda: (outputs, 7, "no-Q", "a full R"), None, 2**30) == (outputs, 7, "no-Q", "a full R")
    with pytest.raises(confined_check.CheckFailed, match="MemoryError"):
        confined_check.run(lambda: bytearray(2**31), None, 2**30)


def test_a_symbolic_link_or_a_huge_file_in_the_submissions_is_graded_as_empty(tmp_path):
    """Submissions copied with their links (a git clone, rsync): Mallory's notebook is a link to the
    course's solved source notebook, Eve's lab folder a link to Alice's. The grader followed both
    and graded the solution and Alice's work as theirs; now both are graded as empty, with a note.
    So is Trudy's valid notebook of 60 MB, which the grader used to read whole (one of some GB takes
    its memory)."""
    submitted = tmp_path / "submissions"
    (submitted / "alice" / TRAIN.id).mkdir(parents=True)
    nbformat.write(submissions.solved(TRAIN), submitted / "alice" / TRAIN.id / TRAIN.notebook_name)
    (submitted / "mallory" / TRAIN.id).mkdir(parents=True)
    (submitted / "mallory" / TRAIN.id / TRAIN.notebook_name).symlink_to(TRAIN.source_notebook)
    (submitted / "eve").mkdir()
    (submitted / "eve" / TRAIN.id).symlink_to(submitted / "alice" / TRAIN.id)
    huge = submissions.solved(TRAIN)
    huge.cells.append(nbformat.v4.new_markdown_cell("z" * 60_000_000))
    (submitted / "trudy" / TRAIN.id).mkdir(parents=True)
    nbformat.write(huge, submitted / "trudy" / TRAIN.id / TRAIN.notebook_name)
    work = tmp_path / "work"
    assert intake.import_submissions(submitted, work, [TRAIN]) == {TRAIN.id: ["alice", "eve", "mallory", "trudy"]}
    release = [c.source for c in cells.read(TRAIN.release_notebook).cells if cells.is_code_answer(c)]
    for student, why in (("mallory", "is a symbolic link"), ("eve", "is a symbolic link"), ("trudy", "bytes, more than")):
        nb = nbformat.read(work / "submitted" / student / TRAIN.id / TRAIN.notebook_name, as_version=4)
        assert [c.source for c in nb.cells if cells.is_code_answer(c)] == release
        [note] = grader_notes(nb)
        assert why in note.text, note


FORK_BOMB = '''import os, sys, time
forked, stopped = 0, 0
try:
    for _ in range(4 * MAX_TASKS):
        if os.fork() == 0:
            time.sleep(30)
            os._exit(0)
        forked += 1
except OSError as error:
    stopped = error.errno
open(sys.argv[1], "w").close()
print(forked, stopped, os.getuid())
'''
"""A bounded fork bomb: it makes the file its argument names, and prints how many children it
made, the error that stopped it and its user ID."""


GRADERS = ["the tests' own user"] + (["nobody"] if os.getuid() == 0 else [])
"""Who starts the launcher: this process's user and, when the tests run as root, a plain user too."""


@pytest.mark.parametrize("grader", GRADERS)
def test_a_fork_bomb_in_a_kernel_stops_at_its_cap(grader):
    """The launcher caps the kernel's processes and threads at sandbox.MAX_TASKS, counted in the
    kernel's own user namespace; a fork bomb stops there (EAGAIN), and its children die with the
    kernel. Linux exempts root's user ID from the cap, so a kernel started by root runs as a user of
    its own (sandbox.kernel_uid): root inside, and the files it makes belong to that user outside.
    Run by root, this test failed on the code before (the bomb made all its 1,024 children)."""
    python, prefix, pythons = sys.executable, [], [sys.prefix, sys.base_prefix, os.path.realpath(sys.executable)]
    if grader == "nobody":
        python, setpriv = "/usr/bin/python3", shutil.which("setpriv")
        assert setpriv and os.path.exists(python), "run as root, this test needs setpriv and Debian's /usr/bin/python3"
        prefix, pythons = [setpriv, "--reuid=nobody", "--regid=nogroup", "--clear-groups"], []
    with tempfile.TemporaryDirectory(prefix="kit-test-") as tmp:  # /tmp, where nobody may look
        folder = Path(tmp)
        shutil.copytree(Path(landlockpy.__file__).parent, folder / "landlockpy")
        shutil.copy(pyseccomp.__file__, folder)  # the launcher's other import
        shutil.copy(sandbox.__file__, folder)
        (folder / "bomb.py").write_text(FORK_BOMB.replace("MAX_TASKS", str(sandbox.MAX_TASKS)))
        made = folder / "made"
        made.mkdir()
        for path in (folder, *folder.rglob("*")):
            path.chmod(0o777 if path == made else 0o755)
        read = [p for p in (*pythons, "/usr", "/lib", "/lib64", "/etc/ld.so.cache", tmp) if os.path.exists(p)]
        launcher = [python, str(folder / "sandbox.py"), *(arg for p in read for arg in ("--read", p)),
                    "--write", str(made), "--"]
        done = subprocess.Popen([*prefix, *launcher, python, "-I", str(folder / "bomb.py"), str(made / "file")],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd="/")
        stdout, stderr = done.communicate(timeout=60)
        owner = (made / "file").stat().st_uid
    assert done.returncode == 0 and stderr == "", stderr
    forked, stopped, uid_inside = (int(word) for word in stdout.split())
    assert (stopped, forked) == (errno.EAGAIN, sandbox.MAX_TASKS - 3), "the launcher, the init and the kernel count too"
    if grader == "nobody":
        assert (uid_inside, owner) == (65534, 65534), "a plain user is itself inside"
    elif os.getuid() != 0:
        assert (uid_inside, owner) == (os.getuid(), os.getuid()), "a plain user is itself inside"
    else:
        assert (uid_inside, owner) == (0, sandbox.KERNEL_UIDS_FROM + done.pid), "root inside, its own user outside"


def test_without_landlocks_signal_scope_the_kernel_still_signals_nothing_outside():
    """Landlock scopes signals only from ABI 6 (Linux 6.12); before it, a kernel run by root in its
    user namespace could signal every root process on the machine (``kill(-1, SIGKILL)``: the
    grader, every other kernel). In its own PID namespace it cannot even name them: here with the
    files layer (Landlock) left out, a process of this test's is out of its reach."""
    sleeper = subprocess.Popen(["sleep", "60"])
    try:
        probe = (f"import os\nfor pid in ({sleeper.pid}, -1):\n    try:\n        os.kill(pid, 0)\n"
                 "        print('ok')\n    except OSError as error:\n        print(type(error).__name__)\n")
        read = [p for p in (sys.prefix, sys.base_prefix, os.path.realpath(sys.executable)) if os.path.exists(p)]
        command = [*sandbox.launcher_command(read, [], ("network",)), sys.executable, "-I", "-c", probe]
        done = subprocess.run(command, capture_output=True, text=True, timeout=60)
    finally:
        sleeper.kill()
        sleeper.wait()
    assert done.stdout.split() == ["ProcessLookupError", "ProcessLookupError"], done.stderr


def test_a_kernel_cannot_reach_the_sockets_in_another_kernels_folder():
    """Landlock (up to ABI 7) does not control connecting to a Unix socket by its path, and a kernel
    started by root holds capabilities over root's files: it could connect to the grader's socket for
    another kernel, in that kernel's private folder, by its path. Run by root, the launcher gives
    each kernel's folders (``--own``) to the kernel's own user with mode 0700, over which no other
    kernel holds a capability: the connection is refused (EACCES). On the code before, it connected.
    Run by a plain user, every kernel is that user, and README states the gap (Named Unix sockets)."""
    read = [p for p in (sys.prefix, sys.base_prefix, os.path.realpath(sys.executable), "/usr/lib", "/lib", "/lib64",
                        "/etc/ld.so.cache") if os.path.exists(p)]
    with tempfile.TemporaryDirectory(prefix="kit-test-") as first, tempfile.TemporaryDirectory(prefix="kit-test-") as second:
        listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        listener.bind(os.path.join(first, "s"))  # as the grader binds its socket in the first kernel's folder
        listener.listen(1)
        try:
            started = subprocess.run([*sandbox.launcher_command(read, [first], sandbox.LAYERS, [first]), sys.executable, "-I", "-c", ""],
                                     capture_output=True, text=True, timeout=60)
            probe = ("import socket\ntry:\n    socket.socket(socket.AF_UNIX).connect(" + repr(os.path.join(first, "s"))
                     + ")\n    print('connected')\nexcept OSError as error:\n    print(error.errno)\n")
            command = [*sandbox.launcher_command(read, [second], sandbox.LAYERS, [second]), sys.executable, "-I", "-c", probe]
            done = subprocess.run(command, capture_output=True, text=True, timeout=60, cwd=second)
        finally:
            listener.close()
    assert started.returncode == 0 and done.returncode == 0 and done.stderr == "", (started.stderr, done.stderr)
    assert done.stdout.strip() == (str(errno.EACCES) if os.getuid() == 0 else "connected")


ATTRIBUTE_PROBE = """import ctypes, os, sys
outside, readable = sys.argv[1], sys.argv[2]
libc = ctypes.CDLL(None, use_errno=True)
def raw(number, *args):
    if libc.syscall(number, *args) == -1:
        raise OSError(ctypes.get_errno(), "")
fd = os.open(readable, os.O_RDONLY)
attempts = {
    "chmod": lambda: os.chmod(outside, 0o644),
    "fchmod of a file open for reading": lambda: os.fchmod(fd, 0o777),
    "fchmodat2": lambda: raw(452, -100, outside.encode(), 0o644, 0),
    "chown": lambda: os.chown(outside, os.getuid(), os.getgid()),
    "fchown": lambda: os.fchown(fd, os.getuid(), os.getgid()),
    "utime": lambda: os.utime(outside, (0, 0)),
    "setxattr": lambda: os.setxattr(readable, "user.kit", b"x"),
    "removexattr": lambda: os.removexattr(readable, "user.kit"),
    "truncate": lambda: os.truncate(outside, 0),
}
for name, attempt in attempts.items():
    try:
        attempt()
        print(name, "ok")
    except OSError as error:
        print(name, error.errno)
"""
"""Tries to change the mode, owner, times and extended attributes of a file outside the kernel's
paths (its first argument) and of a file it may read (its second), and prints each errno."""


def test_a_kernel_changes_no_files_mode_owner_times_attributes_or_length():
    """Landlock does not control chmod, chown, utime or xattrs (nor truncate before ABI 3): a kernel could make any file it can
    name that it owns, or (started by root) that root owns, readable by every user (solutions/,
    /etc/shadow), or lock the grader out of its own code; with a file it may read, fchmod works on
    the descriptor. A seccomp filter refuses each call (EPERM), and the files stay as they were. On
    the code before, every call succeeded (run by root; a plain user owns the files here)."""
    with tempfile.TemporaryDirectory(prefix="kit-test-") as folder:
        outside, readable = Path(folder) / "outside.txt", Path(folder) / "readable" / "lab.py"
        readable.parent.mkdir()
        for path in (outside, readable):
            path.write_text("x")
            path.chmod(0o600)
        before = [(path.stat().st_mode, path.stat().st_mtime) for path in (outside, readable)]
        read = [p for p in (sys.prefix, sys.base_prefix, os.path.realpath(sys.executable), "/usr/lib", "/lib", "/lib64",
                            "/etc/ld.so.cache", str(readable.parent)) if os.path.exists(p)]
        command = [*sandbox.launcher_command(read, [], sandbox.LAYERS), sys.executable, "-I", "-c", ATTRIBUTE_PROBE,
                   str(outside), str(readable)]
        done = subprocess.run(command, capture_output=True, text=True, timeout=60)
        after = [(path.stat().st_mode, path.stat().st_mtime) for path in (outside, readable)]
    assert done.returncode == 0 and done.stderr == "", done.stderr
    seen = dict(line.rsplit(" ", 1) for line in done.stdout.splitlines())
    assert seen == dict.fromkeys(seen, str(errno.EPERM)) and len(seen) == 9, seen
    assert after == before


ERRNO_HELPERS = """import ctypes
libc = ctypes.CDLL(None, use_errno=True)
def check(result):
    if result == -1:
        raise OSError(ctypes.get_errno(), "")
def call(attempt):
    try:
        attempt()
        return "ok"
    except OSError as error:
        return str(error.errno)
"""
"""What the probes below share: the C library, ``check`` (a C call's -1 as its OSError) and ``call``
(an attempt's outcome: "ok", or its errno)."""


IDENTITY_PROBE = ERRNO_HELPERS + """import os, platform
keyctl = {"x86_64": 250, "aarch64": 219}[platform.machine()]
def get_keyring_id():
    check(libc.syscall(keyctl, 0, -4, 0))  # KEYCTL_GET_KEYRING_ID of the user's keyring
effective = next(line.split()[1] for line in open("/proc/self/status") if line.startswith("CapEff"))
def ring_and_watch():
    check(libc.syscall(425, 1, ctypes.create_string_buffer(120)))  # io_uring_setup, the same number on both
    check(libc.inotify_init1(0))
print(call(lambda: os.setresuid(1, 1, 1)), call(lambda: os.setgroups([0])), call(get_keyring_id), call(ring_and_watch),
      effective)
"""
"""Tries to become user 1 (root outside, for a kernel started by root), to change its groups, to
reach its user's keyring, to set up an io_uring and an inotify instance, and prints each errno and
its effective capabilities."""


CHANNEL_PROBE = ERRNO_HELPERS + """import fcntl, os, sys
libc.mmap.restype = ctypes.c_void_p
libc.mmap.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_int, ctypes.c_int, ctypes.c_int, ctypes.c_long]
path = sys.argv[1]
fd = os.open(path, os.O_RDONLY)
page = libc.mmap(None, 4096, 1, 1, fd, 0)  # PROT_READ, MAP_SHARED
flags = ctypes.c_long(0)
print(call(lambda: os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_DONTNEED)),
      call(lambda: check(libc.mincore(ctypes.c_void_p(page), 4096, (ctypes.c_ubyte * 1)()))),
      call(lambda: check(libc.ioctl(fd, 0x40086602, ctypes.byref(flags)))),
      call(lambda: fcntl.fcntl(os.open(os.path.dirname(path), os.O_RDONLY), 1026, 0x80000001)),
      call(lambda: os.preadv(fd, [bytearray(1)], 0, os.RWF_NOWAIT)))
"""
"""Tries, on a file it may read: to empty its pages from the cache and to read which are cached, to
set its flags (chattr), to watch its folder with dnotify, and a read that says whether it was
cached; prints each errno."""


def test_a_kernel_cannot_signal_through_the_page_cache_file_flags_or_dnotify():
    """A third review (helper-55) passed a classmate's functions between kernels through the page
    cache of files every kernel may read (fadvise to empty it, mincore to read it back), set flags
    (chattr) on a plain-user grader's own files for a later kernel, and watched another kernel's reads
    with dnotify. The seccomp filter refuses each (EPERM). On the code before, every call succeeded."""
    with tempfile.TemporaryDirectory(prefix="kit-test-") as folder:
        readable = Path(folder) / "lab.txt"
        readable.write_bytes(b"x" * 8192)
        read = [p for p in (sys.prefix, sys.base_prefix, os.path.realpath(sys.executable), "/usr/lib", "/lib", "/lib64",
                            "/etc/ld.so.cache", folder) if os.path.exists(p)]
        command = [*sandbox.launcher_command(read, [], sandbox.LAYERS), sys.executable, "-I", "-c", CHANNEL_PROBE,
                   str(readable)]
        done = subprocess.run(command, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    assert done.stdout.split() == [str(errno.EPERM)] * 5


NAMESPACE_PROBE = ERRNO_HELPERS + """import os, threading, subprocess, sys
CLONE_NEWUSER, CLONE_NEWNS = 0x10000000, 0x00020000
def clone_new_user():
    check(libc.syscall({"x86_64": 56, "aarch64": 220}[os.uname().machine], CLONE_NEWUSER | 17, 0, 0, 0, 0))
worker = threading.Thread(target=lambda: None)  # threads and processes still start (clone3 falls back to clone)
worker.start()
worker.join()
child = subprocess.run([sys.executable, "-c", "print(1)"], capture_output=True, text=True).stdout.strip()
print(call(lambda: check(libc.unshare(CLONE_NEWUSER))), call(lambda: check(libc.unshare(CLONE_NEWNS))),
      call(clone_new_user), call(lambda: check(libc.setns(os.open("/proc/self/ns/net", os.O_RDONLY), 0))), child)
"""
"""Tries to make a user and a mount namespace (unshare, and clone with CLONE_NEWUSER) and to join one
(setns); prints each errno, after starting a thread and a process as honest code does."""


def probe_outcomes(probe: str) -> list[str]:
    """What a probe prints, run under the whole sandbox with the Python installation, the system's
    libraries and its own /proc entry to read (it must run cleanly: no error, nothing on stderr)."""
    read = [p for p in (sys.prefix, sys.base_prefix, os.path.realpath(sys.executable), "/usr/lib", "/lib", "/lib64",
                        "/etc/ld.so.cache", "/proc/self") if os.path.exists(p)]
    command = [*sandbox.launcher_command(read, [], sandbox.LAYERS), sys.executable, "-I", "-c", probe]
    done = subprocess.run(command, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    return done.stdout.split()


def test_a_kernel_cannot_make_namespaces_whose_counter_every_kernel_reads():
    """A fourth review (helper-56) moved the machine's unique mount-ID counter from one kernel by making
    mount namespaces (unshare(CLONE_NEWUSER), then unshare(CLONE_NEWNS), 7,000 a second) and read it from
    another (statx's STATX_MNT_ID_UNIQUE): 99% of raw bits right between two kernels graded side by
    side. The seccomp filter refuses making or joining namespaces and mounts (EPERM); threads and
    processes still start. On the code before, each call succeeded."""
    assert probe_outcomes(NAMESPACE_PROBE) == [str(errno.EPERM)] * 4 + ["1"]


def test_a_kernel_cannot_change_who_it_is_nor_reach_a_keyring_io_uring_or_inotify():
    """Started by root, a kernel is root in its user namespace, where user 1 is root outside: with
    ``setresuid(1)`` it became root again, free of the cap on its processes (an adversarial review
    forked 400). A user's keyring outlives the kernel, a channel from one submission's kernel to the
    next. The seccomp filter refuses both (EPERM), and the kernel keeps only CAP_DAC_OVERRIDE and
    CAP_DAC_READ_SEARCH (bits 1 and 2: 0x6). On the code before, both calls succeeded, with every
    capability. A re-attack then set an xattr through io_uring, whose operations are not system calls,
    and watched folders it may not read with inotify: both are refused too (on c7463c6, io_uring_setup
    and inotify_init1 succeeded)."""
    assert probe_outcomes(IDENTITY_PROBE) == [str(errno.EPERM)] * 4 + ["0000000000000006"]


def test_a_kernel_run_by_root_changes_no_access_time():
    """Landlock does not control stat(): a re-attack passed a classmate's functions from one kernel
    to a later one through the access times of files every kernel may read, set by reading them at
    chosen moments (a blank notebook scored 9/9, unflagged, with the sandbox on). Run by root, the
    launcher binds the kernel's paths over themselves with noatime in a mount namespace of its own,
    so a read changes no access time. Run by a plain user the mounts are locked and README states
    the gap (Covert channels). On the code before, the read set the file's access time to now; with
    only the kernel's own paths bound noatime (3f70a17), a link outside them still took the time when
    the kernel read it (a third review passed functions through links' access times)."""
    with tempfile.TemporaryDirectory(prefix="kit-test-") as folder:
        (Path(folder) / "readable").mkdir()
        shared, link = Path(folder) / "readable" / "shared.txt", Path(folder) / "link"
        shared.write_text("x")
        link.symlink_to(shared)  # outside every path the kernel may read: following it sets its own access time
        for path in (shared, link):  # read long ago, written since: a read updates it
            os.utime(path, (1_000_000_000, 2_000_000_000), follow_symlinks=False)
        read = [p for p in (sys.prefix, sys.base_prefix, os.path.realpath(sys.executable), "/usr/lib", "/lib", "/lib64",
                            "/etc/ld.so.cache", str(shared.parent)) if os.path.exists(p)]
        probe = f"import os\nprint(open({str(shared)!r}).read(), os.readlink({str(link)!r}) == {str(shared)!r})"
        done = subprocess.run([*sandbox.launcher_command(read, [], sandbox.LAYERS), sys.executable, "-I", "-c", probe],
                              capture_output=True, text=True, timeout=60)
        atimes = [os.stat(path, follow_symlinks=False).st_atime for path in (shared, link)]
    assert done.returncode == 0 and done.stderr == "" and done.stdout == "x True\n", done.stderr
    assert (atimes == [1_000_000_000] * 2) == (os.getuid() == 0), atimes


def test_a_crashing_kernel_dumps_no_core():
    """A kernel that raises its core size limit and crashes wrote its memory (up to 4 GiB) into its
    folder (the core pattern here), or, where a helper collects cores (systemd-coredump, apport),
    outside the sandbox, once per restart; the launcher sets the limit to 0 for good."""
    with tempfile.TemporaryDirectory(prefix="kit-test-") as folder:
        probe = ("import os, resource, signal\ntry:\n    resource.setrlimit(resource.RLIMIT_CORE, (-1, -1))\n"
                 "except ValueError as error:\n    print(error, flush=True)\nbuffer = bytearray(50 << 20)\n"
                 "os.kill(os.getpid(), signal.SIGSEGV)\n")
        read = [p for p in (sys.prefix, sys.base_prefix, os.path.realpath(sys.executable), "/usr/lib", "/lib", "/lib64",
                            "/etc/ld.so.cache") if os.path.exists(p)]
        command = [*sandbox.launcher_command(read, [folder], sandbox.LAYERS), sys.executable, "-I", "-c", probe]
        done = subprocess.run(command, capture_output=True, text=True, timeout=60, cwd=folder)
        left = os.listdir(folder)
    assert done.returncode == 128 + signal.SIGSEGV and done.stdout == "not allowed to raise maximum limit\n", done
    assert left == [], "the crash left a core dump"


def test_widget_messages_neither_bloat_nor_break_the_graded_notebook(runs):
    """A kernel can send widgets' messages (comm) of its own making: nbclient kept their state in
    the graded notebook without limit (10 MB here), and a widget without its module made it raise,
    which ended the grading of the submission. The grader drops them."""
    nb, _ = runs["messages"]
    assert "widgets" not in nb.metadata and len(nbformat.writes(nb)) < 100_000


def test_a_huge_message_from_the_kernel_never_reaches_the_grader(runs):
    """A message of 150 MB on the kernel's standard output: jupyter_client decoded it whole, and
    the grader held several times its size (1.4 GiB for messages of 300 MB), whatever the output cap
    kept. ZeroMQ now refuses a message over the cap (128 MiB; 16 MiB here) before the grader
    reads it; the cell that sent it times out, and grading goes on."""
    nb, peak = runs["messages"]
    *_, flooded, after = nb.cells
    assert peak < 450 * 2**20, f"the grader grew to {peak / 2**20:.0f} MiB"
    assert [o.get("ename") for o in flooded.outputs] == ["CellTimeoutError"]
    assert [o.get("text") for o in after.outputs] == ["graded on\n"]


def test_a_submissions_html_is_inert_where_the_instructor_views_it(runs):
    """nbgrader's formgrader shows a graded notebook as a page of the instructor's Jupyter server, and
    rendered a script in a student's Markdown answer or displayed output as live HTML: it ran as the
    instructor, with the server's API (the reference, terminals, the grades). The course's autograde
    runs InertHtml right after the kernel and the integrity flags (whose notes quote the student's code),
    before anything is saved; the page then holds the text, and no script (tests/test_hostile_pages.py
    opens formgrader and the feedback page in Chromium)."""
    preprocessors = nbgrader_apps.course_config().Autograde.autograde_preprocessors
    names = [p.__name__ for p in preprocessors]
    assert names.index("InertHtml") == names.index("FlagCheating") + 1 == names.index("GradingExecute") + 2, names
    nb = copy.deepcopy(runs["wire"][0])
    nb.cells.append(nbformat.v4.new_markdown_cell(
        "My derivation: $x<y$. <!-- a note --!><img src=x onerror=\"alert('answer')\"> --> <script>alert('answer')</script>"))
    nb, _ = InertHtml().preprocess(nb, {})
    config = Config()
    config.HTMLExporter.template_name = "formgrade"
    config.HTMLExporter.extra_template_basedirs = [formgrader_handlers.template_path]
    page, _ = HTMLExporter(config=config).from_notebook_node(nb, resources={
        "index": 0, "total": 1, "base_url": "/", "notebook_id": TRAIN.id, "nbgrader": {}})
    for live in ("<script>alert(", "<img src=x onerror", "alert('js')\n</script>"):  # as tags, not as text
        assert live not in page, live
    assert "$x&lt;y$" in page, "the answer's text reads as written"

"""nbgrader's Execute preprocessor, made safe for a whole class.

``GradingExecute`` runs a submission cell by cell, like nbgrader's Execute, and adds:

- hidden tests run in the grader's process, never in the student's kernel (autograder/pipeline/check_runner.py),
  on cases drawn from the submission's own seed, which the kernel never sees (grading_secret.py):
  a test cell's visible part runs in the kernel, then its check runs here against the student's
  function, which the kernel only calls, in a forked child capped in memory and killed at the
  cell's deadline (autograder/pipeline/confined_check.py), with what the student's function printed kept
  within the output caps; the grader refuses to start if it cannot import the checks
  and the reference they compare with (without them every hidden test would fail and nbgrader
  would still report success);
- caps on each kernel: address space (``memory_limit_gb``), time per cell (``timeout``, the visible
  part and the hidden test together), time for the whole notebook (``notebook_timeout``), and
  output kept per cell and per notebook (``max_output_bytes``, ``max_notebook_output_bytes``: printed
  text, displayed data and results alike);
- a kernel that does not start (on a loaded machine a start can take minutes) is started again,
  up to ``kernel_start_attempts`` times in all, rather than nbgrader dropping the submission;
- recovery: when the kernel dies (``os._exit``, a crash, the memory cap) or a cell times out, the
  cell gets an error that says so, a fresh kernel replays the cells before it silently, and
  grading goes on. nbgrader alone throws the whole submission away when its kernel dies.

``nbgrader_config.py`` puts it in place of Execute, so plain ``nbgrader autograde`` gets all this.
"""

from __future__ import annotations

import contextlib
import functools
import json
import os
import shutil
import tempfile
import time

from jupyter_core.utils import ensure_async, run_sync
from nbclient import NotebookClient
from nbclient.exceptions import CellTimeoutError, DeadKernelError
from nbformat import NotebookNode, ValidationError
from nbformat.v4 import new_output
from nbgrader.preprocessors import Execute
from traitlets import Float, Integer

from autograder import cells
from autograder.kernel import sandbox
from autograder.kernel.remove_tree import remove_tree
from autograder.hidden_tests import cases
from autograder.kernel.wire import PeerTimeout
from autograder.pipeline import confined_check, grading_secret, hidden_blocks, kernel_code, verdicts
from autograder.pipeline.check_runner import run_check
from autograder.pipeline.kernel_connection import KernelStopped, Listener, connect, stop
from autograder.pipeline.output_caps import OutputBudget, cut, error_output
from autograder.pipeline.restore import NoteKind, add_grader_notes

TIMEOUT_ERROR = "CellTimeoutError"
KERNEL_DIED = "KernelDied"
NOT_RUN = "NotRun"


class GradingExecute(Execute):
    """nbgrader's Execute with hidden tests in the grader's process, caps and kernel recovery."""

    memory_limit_gb = Float(4.0, help="Address-space cap of each grading kernel, GiB (0: none).").tag(config=True)
    notebook_timeout = Integer(300, help="Seconds for a whole submission; later cells are not run.").tag(config=True)
    max_output_bytes = Integer(1_000_000, help="Output kept per cell (printed text, displayed data, results), in "
                               "characters; the rest is dropped.").tag(config=True)
    max_notebook_output_bytes = Integer(10_000_000, help="Output kept for a whole submission, in characters; "
                                        "later output is dropped.").tag(config=True)
    max_restarts = Integer(12, help="Kernel restarts per submission before the rest is not run.").tag(config=True)
    kernel_start_attempts = Integer(3, help="Kernel starts tried before a submission is given up.").tag(config=True)

    def _memory_bytes(self) -> int:
        """The memory cap, in bytes, of each kernel and of each hidden test's check (0: none)."""
        return int(max(0.0, self.memory_limit_gb) * 2**30)

    def _setup_code(self) -> list[tuple[str, str]]:
        """(what it is, code) run silently in every new kernel before any student cell."""
        steps = [("the grader's kernel-side module", kernel_code.kernel_setup_code())]
        if self.memory_limit_gb > 0:
            cap = self._memory_bytes()
            steps.append(("the memory cap", f"__import__('resource').setrlimit(__import__('resource').RLIMIT_AS, ({cap}, {cap}))"))
        return steps

    async def async_start_new_kernel_client(self):
        kc = await self._async_start_kernel_client_with_retries()
        for what, code in self._setup_code():
            msg_id = await ensure_async(kc.execute(code, silent=True, store_history=False))
            reply = await self.async_wait_for_reply(msg_id)
            if reply is None or reply["content"]["status"] != "ok":
                await self._async_cleanup_kernel()
                raise RuntimeError(f"{what} did not install in the grading kernel: {reply and reply['content']}")
        return kc

    async def _async_start_kernel_client_with_retries(self):
        """nbclient's client start, tried again with a fresh kernel when the kernel does not answer."""
        for attempt in range(1, self.kernel_start_attempts + 1):
            try:
                return await super().async_start_new_kernel_client()
            except RuntimeError as error:  # nbclient: "Kernel didn't respond in 180 seconds", or it died
                if attempt == self.kernel_start_attempts:
                    raise
                self.log.warning("The grading kernel did not start (%s); starting another (attempt %d of %d).",
                                 error, attempt + 1, self.kernel_start_attempts)
                # nbclient has shut the failed kernel down and, having made a client, dropped its manager
                if self.km is None:
                    self.km = self.create_kernel_manager()
                await self.async_start_new_kernel()

    # nbclient binds the synchronous twin to the base class's coroutine; bind it to ours.
    start_new_kernel_client = run_sync(async_start_new_kernel_client)

    def preprocess(self, nb: NotebookNode, resources=None, km=None):
        """Execute every code cell, recovering from dead and stuck kernels (see the module doc)."""
        _warn_once_if_not_sandboxed(self.log)
        NotebookClient.__init__(self, nb, km)
        tests = hidden_blocks.hidden_tests(nb)
        checks = {index: test.load() for index, test in tests.items()}  # ReferenceUnavailable before any kernel starts
        hidden_blocks.prepare(tests.values())
        self.reset_execution_trackers()
        self._check_assign_resources(resources)
        with _scratch_copy(self.resources) as scratch:
            # the hidden cases of this submission, drawn from a seed that its kernel never sees, of
            # everything the kernel can read of the submission: its cells and its folder's files
            seed = cases.seed_for(grading_secret.secret(), grading_secret.submission_content(nb, scratch))
            with cases.seeded(seed):
                return self._execute_cells(tests, checks)

    def _execute_cells(self, tests: dict[int, hidden_blocks.HiddenTest], checks: dict) -> tuple[NotebookNode, dict]:
        """``preprocess`` in the kernel's folder: every code cell, hidden tests in this process."""
        self._output = OutputBudget(self.max_output_bytes, self.max_notebook_output_bytes)
        self.resources[verdicts.RESOURCES_KEY] = {}
        verdicts.forget_diagnoses(self.nb)
        notes: list[str] = []
        self._stopped: set[int] = set()
        deadline = time.monotonic() + self.notebook_timeout
        failed: set[int] = set()
        restarts = 0
        with self.setup_kernel():
            info = self.wait_for_reply(self.kc.kernel_info())
            self.nb.metadata["language_info"] = info["content"]["language_info"]
            for index, cell in enumerate(self.nb.cells):
                if cell.cell_type != "code":
                    continue
                if time.monotonic() > deadline or restarts > self.max_restarts:
                    why = (f"the submission used up its time limit of {self.notebook_timeout} s"
                           if restarts <= self.max_restarts else "the kernel had to be restarted too often")
                    _add_error(cell, NOT_RUN, f"This cell was not run: {why}.")
                    self._fail(cell, f"it was not run: {why}")
                    if not any(note.startswith("The cells from") for note in notes):
                        notes.append(f"The cells from cell {_name(cell, index)} on were not run: {why}.")
                    continue
                stopped = (f"This cell ran for more than {self.timeout} s and was stopped. The grader "
                           "restarted the kernel, re-ran the cells above, and went on without this one.")
                try:
                    if index in tests:
                        # the blanks whose hidden tests come before this one in the notebook, however
                        # those cells ended: a blank whose own test cell hung or killed the kernel is
                        # still served by the reference to the blanks after it, as partial credit needs
                        earlier = frozenset(test.blank for at, test in tests.items() if at < index)
                        self._execute_test_cell(cell, index, tests[index], checks[index], earlier)
                    else:
                        self.execute_cell(cell, index, store_history=True)
                except DeadKernelError:
                    notes.append(f"The kernel died in cell {_name(cell, index)}; it was restarted and the cells "
                                 "above it were run again.")
                    _shown_only(cell)
                    _add_error(cell, KERNEL_DIED, "The kernel died while running this cell (it crashed, "
                               "called os._exit, or went over the memory limit). The grader restarted it, "
                               "re-ran the cells above, and went on without this one.")
                    self._fail(cell, "the kernel died while it ran")
                except CellTimeoutError:
                    notes.append(self._stop_note(cell, index))
                    _shown_only(cell)
                    _add_error(cell, TIMEOUT_ERROR, stopped)
                    self._fail(cell, f"it ran for more than {self.timeout} s and was stopped")
                else:
                    if id(cell) not in self._stopped:
                        continue
                    # the grader stopped it (``_async_handle_timeout``): its error, and the KeyboardInterrupt that
                    # stopping it raised, are the grader's doing; an error that the kernel named so is not
                    cell.outputs = [o for o in cell.outputs if o.get("ename") not in (TIMEOUT_ERROR, "KeyboardInterrupt")]
                    _shown_only(cell)
                    _add_error(cell, TIMEOUT_ERROR, stopped)
                    notes.append(self._stop_note(cell, index))
                    self._fail(cell, f"it ran for more than {self.timeout} s and was stopped")
                failed.add(index)
                restarts += 1
                self._restart_and_replay(index, failed, deadline)
        notes += self._output.notes(lambda i: _name(self.nb.cells[i], i))
        verdicts.record_visible_checks(self.nb, NOT_RUN)
        _whole_execution_counts(self.nb)
        add_grader_notes(self.nb, first_cause(self.nb), NoteKind.CAUSE)
        add_grader_notes(self.nb, notes)
        self.set_widgets_metadata()
        return self.nb, self.resources

    def _execute_test_cell(self, cell: NotebookNode, index: int, test: hidden_blocks.HiddenTest, check, earlier: frozenset[str]) -> None:
        """Run the visible part of a test cell in the kernel, then its hidden test here
        (autograder/pipeline/check_runner.py), and record the grader's verdict (autograder/pipeline/verdicts.py).
        The cell shows what the visible part showed, made unable to score (``verdicts.display_only``),
        then what the student's function printed during the hidden test, then the hidden test's
        failure if it failed. Raises CellTimeoutError or DeadKernelError as ``execute_cell`` does;
        a visible part that was stopped is left for the caller to report."""
        start = time.monotonic()
        source = cell.source
        cell.source = hidden_blocks.split(source)[0]
        try:
            self.execute_cell(cell, index, store_history=True)
        finally:
            cell.source = source
        if id(cell) in self._stopped:
            return  # stopped: the caller restarts the kernel and records the failure
        cell.outputs = [verdicts.display_only(o) for o in cell.outputs]
        deadline = start + self.timeout if self.timeout else None
        listener = Listener(getattr(self.km, "private_folder", None))  # the sandbox lets the kernel reach it
        msg_id = self.kc.execute(kernel_code.serve_code(listener.path, test), silent=True,
                                 store_history=False, allow_stdin=False)
        try:
            peer, why_not = connect(listener, deadline, lambda: self._replied(msg_id))
            printed = room = 0
            mistake = wrong_on = None
            if peer is None:
                outputs = [error_output("AssertionError", why_not)]
            else:
                try:
                    room = self._output.room(index)
                    outputs, printed, mistake, wrong_on = confined_check.run(lambda: run_check(peer, test, check, earlier, room),
                                                          deadline, self._memory_bytes())
                except KernelStopped:
                    if not self._finished_alive(msg_id):
                        raise DeadKernelError("Kernel died") from None
                    outputs = [error_output(
                        "AssertionError", f"The hidden test of {test.blank} could not finish: your code ended the "
                        "grader's connection to the kernel (with sys.exit, or by closing sockets).")]
                finally:
                    stop(peer)
        except PeerTimeout:
            raise CellTimeoutError.error_from_timeout_and_cell("Cell execution timed out", self.timeout, cell) from None
        finally:
            listener.close()
        failures = [o for o in outputs if o.output_type == "error"]
        cell.outputs += outputs
        if printed:
            self._output.count(cell, index, printed, min(printed, room))  # after them: its note ends the cell
        if failures:
            self._fail(cell, f"{failures[0].ename}: {failures[0].evalue}")
            if mistake is not None:
                verdicts.record_diagnosis(cell, mistake)
            if wrong_on is not None:
                verdicts.record_wrong_only(cell, wrong_on)
        else:
            verdicts.record(self.resources, cells.grade_id(cell), passed=True)
        self._wait_served(msg_id)

    def _fail(self, cell: NotebookNode, why: str) -> None:
        """Record that the test cell ``cell`` (if it is one) fails, and why."""
        if cells.is_autograded_test(cell):
            verdicts.record(self.resources, cells.grade_id(cell), passed=False, why=why)

    def _replied(self, msg_id: str) -> bool:
        """Whether the kernel has finished the silent execution ``msg_id`` (then it will not connect)."""
        async def replied() -> bool:
            while await self.kc.shell_channel.msg_ready():
                reply = await self.kc.shell_channel.get_msg(timeout=0)
                if reply["parent_header"].get("msg_id") == msg_id:
                    self._served_reply = msg_id
                    return True
            return False

        return run_sync(replied)()

    def _finished_alive(self, msg_id: str, patience_s: float = 10.0) -> bool:
        """After the kernel closed the hidden test's connection: True once it has finished serving
        and is alive (the student's code ended the connection), False once it is dead, or if neither
        is known within ``patience_s`` (then it is restarted like a dead one). A dead kernel can still
        look alive for a moment after its connection closes."""
        deadline = time.monotonic() + patience_s
        while time.monotonic() < deadline:
            if not run_sync(self.km.is_alive)():
                return False
            if self._replied(msg_id):
                return True
            time.sleep(0.05)
        return False

    def _wait_served(self, msg_id: str) -> None:
        """Wait for the kernel to finish serving the hidden test (it stops when told to)."""
        if getattr(self, "_served_reply", None) == msg_id:
            return
        self.wait_for_reply(msg_id)

    def _stop_note(self, cell: NotebookNode, index: int) -> str:
        """The grader's note on a cell it stopped, saying whether the stop cost marks (a review of issue 30: a
        student read the note on a slow figure cell as a lost test)."""
        note = f"Cell {_name(cell, index)} ran for more than {self.timeout} s and was stopped."
        if cells.is_autograded_test(cell):
            return note
        return note + " It is not graded, so this cost no marks, but what it shows is missing from your feedback."

    async def _async_handle_timeout(self, timeout: int, cell: NotebookNode | None = None) -> dict | None:
        """nbclient's: interrupt the kernel, and reply with a CellTimeoutError. The cell is recorded as
        stopped here, in the grader's process: an error of that name from the kernel is the student's own
        output, not a stop (a review of issue 31 faked one to skip a hidden test and write the report's detail)."""
        if cell is not None:
            self._stopped.add(id(cell))
        return await super()._async_handle_timeout(timeout, cell)

    def _restart_and_replay(self, upto: int, failed: set[int], deadline: float) -> None:
        """A fresh kernel that has silently run every code cell before ``upto`` that did not fail."""
        run_sync(self._async_restart)()
        for index, cell in enumerate(self.nb.cells[:upto]):
            if cell.cell_type != "code" or index in failed or time.monotonic() > deadline:
                continue
            source = hidden_blocks.split(cell.source)[0]  # a hidden test never runs in the kernel
            msg_id = self.kc.execute(source, silent=True, store_history=False, allow_stdin=False)
            self._stopped.discard(id(cell))
            try:
                reply = self.wait_for_reply(msg_id, cell)
            except (DeadKernelError, CellTimeoutError):
                reply = None
            if reply is None or id(cell) in self._stopped:
                failed.add(index)
                run_sync(self._async_restart)()

    async def _async_restart(self) -> None:
        await self._async_cleanup_kernel()
        self.km = self.create_kernel_manager()
        await self.async_start_new_kernel()
        await self.async_start_new_kernel_client()

    def process_message(self, msg: dict, cell: NotebookNode, cell_index: int) -> NotebookNode | None:
        """``_capped_message``, which drops a message that nbclient cannot make a valid output of: a
        kernel can send anything on its own channel (an execution count or a stream's text that is
        not what nbformat allows), nbclient then raised, and nbgrader gave up on the whole submission."""
        try:
            return self._capped_message(msg, cell, cell_index)
        except (ValidationError, KeyError, TypeError, ValueError, AttributeError) as error:
            self.log.warning("A %s message from the kernel was dropped: %s", msg.get("msg_type"), str(error)[:200])
            return None

    def _capped_message(self, msg: dict, cell: NotebookNode, cell_index: int) -> NotebookNode | None:
        """nbclient's handling of a kernel message, with output capped: printed text, displayed data
        and results together keep at most ``max_output_bytes`` characters of a cell and
        ``max_notebook_output_bytes`` of the notebook, then the cell says that the rest was dropped
        (the rest of a text is cut, any later output dropped). An error is always kept, its name,
        message and traceback lines cut to output_caps.MAX_MESSAGE_CHARS: dropping it would turn a
        failing test cell into a passing one. Widgets' messages (``comm_*``) are dropped: nbclient
        would keep their state, of any size, in the graded notebook, and a malformed one made it
        raise and end the grading of the submission."""
        kind, content = msg["msg_type"], msg["content"]
        if kind.startswith("comm"):
            return None
        if kind == "error":
            return super().process_message({**msg, "content": _cut_error(content)}, cell, cell_index)
        if kind not in ("stream", "display_data", "execute_result", "update_display_data"):
            return super().process_message(msg, cell, cell_index)
        if kind == "stream":
            size = len(content.get("text", ""))
        else:
            size = len(json.dumps([content.get("data"), content.get("metadata")]))
        room, out = self._output.room(cell_index), None
        kept = size if size <= room else room if kind == "stream" else 0
        if kept == size:
            out = super().process_message(msg, cell, cell_index)
        elif kept:
            out = super().process_message({**msg, "content": {**content, "text": content["text"][:kept]}}, cell, cell_index)
        self._output.count(cell, cell_index, size, kept)
        return out

    def on_cell_executed(self, **kwargs) -> None:
        """nbgrader's, which adds the execute reply's error to the cell when the kernel showed none,
        with that error cut as ``process_message`` cuts one (the kernel writes the reply too)."""
        reply = kwargs["execute_reply"]
        if reply["content"].get("status") == "error":
            kwargs["execute_reply"] = {**reply, "content": _cut_error(reply["content"])}
        return super().on_cell_executed(**kwargs)


@contextlib.contextmanager
def _scratch_copy(resources: dict):
    """Run the kernel in a scratch copy of the submission's folder (its regular files), not in the
    folder itself: nbgrader writes the graded notebook into that folder after the kernel is gone,
    and a kernel that could write there could leave a symbolic link in the notebook's place that
    sends nbgrader's write to the gradebook or another student's file. The copies have the bytes
    only, with a new file's mode and times: a file's mode bits and times are not part of the seed
    (grading_secret.submission_content), so a student who chose them could hand in answers in them
    to their own hidden cases (plain nbgrader autograde keeps them; the fourth review found it).
    Yields the scratch folder."""
    metadata = resources.setdefault("metadata", {})
    folder = metadata.get("path")
    scratch = tempfile.mkdtemp(prefix="kit-work-")
    try:
        if folder and os.path.isdir(folder):
            for entry in os.scandir(folder):
                if entry.is_file(follow_symlinks=False):
                    shutil.copyfile(entry.path, os.path.join(scratch, entry.name), follow_symlinks=False)
        metadata["path"] = scratch
        yield scratch
    finally:
        metadata["path"] = folder
        remove_tree(scratch)  # the kernel wrote in it: of any depth (autograder/kernel/remove_tree.py)


@functools.cache
def _warn_once_if_not_sandboxed(log) -> None:
    """Say once per grading process, in nbgrader's log, that the kernels are not fully sandboxed."""
    status = sandbox.status()
    if not status.complete:
        log.warning("%s. See README (The grading kernel's sandbox).", status.summary)


def _name(cell: NotebookNode, index: int) -> str:
    """How a note names a cell: its nbgrader id, or its position."""
    return cells.grade_id(cell) if "grade_id" in cells.meta(cell) else str(index + 1)


SETUP = "setup"
"""The grade_id of every lab's set-up cell."""
FAILED_AS_IT_RAN = "failed when the grader ran it"
NOT_A_CAUSE = {"NotWrittenYet", TIMEOUT_ERROR, KERNEL_DIED, NOT_RUN}
"""Errors that are no cell's own failure, or that have a note of their own: a blank still unwritten, and
the grader's stops."""


def first_cause(nb: NotebookNode) -> list[str]:
    """A note that leads with the first set-up or answer cell that failed when it ran, if a test cell
    after it failed too: the set-up cell's imports, or the functions an answer cell defines after its
    failing line, are then missing from every cell below, which fail with errors (often a NameError)
    that do not say why. Empty if there is no such cell.

    It reads the error the kernel reported, so a submission can make this note say what it likes;
    it is only a message (the score is the grader's verdict: autograder/pipeline/verdicts.py), and
    it is shown as text (``add_grader_notes`` escapes it)."""
    code = [c for c in nb.cells if c.cell_type == "code"]
    for at, cell in enumerate(code):
        setup = cells.meta(cell).get("grade_id") == SETUP
        if not setup and not cells.is_code_answer(cell):
            continue
        errors = [o for o in cell.outputs if o.get("output_type") == "error" and o.get("ename") not in NOT_A_CAUSE]
        later = [c for c in code[at + 1:] if cells.is_autograded_test(c) and any(o.get("output_type") == "error" for o in c.outputs)]
        if not errors or not later:
            continue
        message = str(errors[0].get("evalue", "")).strip().splitlines()
        error = f"{errors[0].get('ename')}: {message[0][:200] if message else ''}".rstrip(": ")
        if setup:
            return [f"The set-up cell {FAILED_AS_IT_RAN} ({error}). Every cell after it needs what it "
                    "imports, so the errors below may all come from this one."]
        return [f"Your cell {cells.grade_id(cell)} {FAILED_AS_IT_RAN} ({error}), so what it defines after "
                "the failing line was never defined: the cells below that use it fail because of this error. "
                "Fix it first."]
    return []


def _shown_only(cell: NotebookNode) -> None:
    """A stopped or killed test cell's outputs from the kernel, made unable to score or to be taken for the grader's
    reason (``verdicts.display_only``), as a test cell's are when it runs to the end: the grader's error is then the
    cell's only error (adversarial review of issue 31: a kernel's error text led the grades CSV's reason)."""
    if cells.is_autograded_test(cell):
        cell.outputs = [verdicts.display_only(o) for o in cell.outputs]


def _cut_error(content: dict) -> dict:
    """An error's content with its name, message and traceback lines cut to output_caps.MAX_MESSAGE_CHARS."""
    return {**content, **{key: cut(str(content.get(key, ""))) for key in ("ename", "evalue")},
            "traceback": [cut(str(line)) for line in content.get("traceback", [])]}


def _whole_execution_counts(nb: NotebookNode) -> None:
    """Every execution count in the notebook a whole number or None: the kernel writes them (a forged
    message can say anything), and nbconvert rejects a notebook whose count is not a number, which
    made nbgrader give up on the whole submission."""
    def whole(value):
        return value if isinstance(value, int) and not isinstance(value, bool) and value >= 0 else None

    for cell in nb.cells:
        if cell.cell_type == "code":
            cell.execution_count = whole(cell.get("execution_count"))
            for output in cell.outputs:
                if output.get("output_type") == "execute_result":
                    output["execution_count"] = whole(output.get("execution_count"))


def _add_error(cell: NotebookNode, ename: str, evalue: str) -> None:
    cell.outputs.append(new_output("error", ename=ename, evalue=evalue, traceback=[f"{ename}: {evalue}"]))

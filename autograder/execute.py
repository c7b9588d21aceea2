"""nbgrader's Execute preprocessor, made safe for a whole class.

``GradingExecute`` runs a submission cell by cell, like nbgrader's Execute, and adds:

- a refusal to grade in a kernel that cannot import the reference ``solutions`` (without it every
  hidden test fails with ModuleNotFoundError and nbgrader still reports success);
- caps on each kernel: address space (``memory_limit_gb``), time per cell (``timeout``), time for
  the whole notebook (``notebook_timeout``), and output kept per cell (``max_output_bytes``);
- the integrity monitor (autograder/integrity.py): installed before any student cell, and probed
  after each graded test cell; its findings go to ``resources["integrity_findings"]`` for
  ``FlagCheating``;
- a kernel that does not start (on a loaded machine a start can take minutes) is started again,
  up to ``kernel_start_attempts`` times in all, rather than nbgrader dropping the submission;
- recovery: when the kernel dies (``os._exit``, a crash, the memory cap) or a cell times out, the
  cell gets an error that says so, a fresh kernel replays the cells before it silently, and
  grading goes on. nbgrader alone throws the whole submission away when its kernel dies.

``nbgrader_config.py`` puts it in place of Execute, so plain ``nbgrader autograde`` gets all this.
"""

from __future__ import annotations

import time

from jupyter_core.utils import ensure_async, run_sync
from nbclient import NotebookClient
from nbclient.exceptions import CellTimeoutError, DeadKernelError
from nbformat import NotebookNode
from nbformat.v4 import new_output
from nbgrader.preprocessors import Execute
from traitlets import Float, Integer

from autograder import cells
from autograder.integrity import INTEGRITY_SETUP, PROBE_NAME, RUNTIME_PROBE, runtime_findings
from autograder.restore_cells import add_grader_notes

PROBE = "__import__('solutions')"
TIMEOUT_ERROR = "CellTimeoutError"
KERNEL_DIED = "KernelDied"
NOT_RUN = "NotRun"


class ReferenceUnavailable(RuntimeError):
    """The grading kernel cannot import the hidden ``solutions`` package."""


class GradingExecute(Execute):
    """nbgrader's Execute with caps, kernel recovery and the reference check."""

    memory_limit_gb = Float(4.0, help="Address-space cap of each grading kernel, GiB (0: none).").tag(config=True)
    notebook_timeout = Integer(300, help="Seconds for a whole submission; later cells are not run.").tag(config=True)
    max_output_bytes = Integer(1_000_000, help="Text output kept per cell; the rest is dropped.").tag(config=True)
    max_restarts = Integer(12, help="Kernel restarts per submission before the rest is not run.").tag(config=True)
    kernel_start_attempts = Integer(3, help="Kernel starts tried before a submission is given up.").tag(config=True)

    def _setup_code(self) -> str:
        lines = [PROBE]
        if self.memory_limit_gb > 0:
            cap = int(self.memory_limit_gb * 2**30)
            lines.append(f"__import__('resource').setrlimit(__import__('resource').RLIMIT_AS, ({cap}, {cap}))")
        return "\n".join(lines)

    async def async_start_new_kernel_client(self):
        kc = await self._async_start_kernel_client_with_retries()
        msg_id = await ensure_async(kc.execute(self._setup_code(), silent=True, store_history=False))
        reply = await self.async_wait_for_reply(msg_id)
        if reply is None or reply["content"]["status"] != "ok":
            content = reply["content"] if reply else {}
            await self._async_cleanup_kernel()
            raise ReferenceUnavailable(
                "The grading kernel cannot import the hidden reference package `solutions` "
                f"({content.get('ename', 'no reply')}: {content.get('evalue', '')}). Every hidden test "
                "would fail, so nothing was graded. Run nbgrader from the course root, whose "
                "nbgrader_config.py puts the root on the kernel's PYTHONPATH."
            )
        msg_id = await ensure_async(kc.execute(INTEGRITY_SETUP, silent=True, store_history=False))
        reply = await self.async_wait_for_reply(msg_id)
        if reply is None or reply["content"]["status"] != "ok":
            await self._async_cleanup_kernel()
            raise RuntimeError(f"The integrity monitor did not install in the grading kernel: {reply and reply['content']}")
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
        NotebookClient.__init__(self, nb, km)
        self.reset_execution_trackers()
        self._check_assign_resources(resources)
        self._output_bytes: dict[int, int] = {}
        notes: list[str] = []
        self.resources["integrity_findings"] = findings = []
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
                    if not any(note.startswith("The cells from") for note in notes):
                        notes.append(f"The cells from cell {_name(cell, index)} on were not run: {why}.")
                    continue
                stopped = (f"This cell ran for more than {self.timeout} s and was stopped. The grader "
                           "restarted the kernel, re-ran the cells above, and went on without this one.")
                try:
                    self.execute_cell(cell, index, store_history=True)
                except DeadKernelError:
                    notes.append(f"The kernel died in cell {_name(cell, index)}; it was restarted and the cells "
                                 "above it were run again.")
                    _add_error(cell, KERNEL_DIED, "The kernel died while running this cell (it crashed, "
                               "called os._exit, or went over the memory limit). The grader restarted it, "
                               "re-ran the cells above, and went on without this one.")
                except CellTimeoutError:
                    notes.append(f"Cell {_name(cell, index)} ran for more than {self.timeout} s and was stopped.")
                    _add_error(cell, TIMEOUT_ERROR, stopped)
                else:
                    timeouts = [o for o in cell.outputs if o.output_type == "error" and o.ename == TIMEOUT_ERROR]
                    if not timeouts:
                        if cells.meta(cell).get("grade") and not cells.meta(cell).get("solution"):
                            findings += [f for f in self._probe(_name(cell, index)) if f not in findings]
                        continue
                    timeouts[-1]["evalue"] = stopped
                    timeouts[-1]["traceback"] = [f"{TIMEOUT_ERROR}: {stopped}"]
                    # the KeyboardInterrupt that stopping it raised is the grader's doing, not the student's
                    cell.outputs = [o for o in cell.outputs if o.get("ename") != "KeyboardInterrupt"]
                    notes.append(f"Cell {_name(cell, index)} ran for more than {self.timeout} s and was stopped.")
                failed.add(index)
                restarts += 1
                self._restart_and_replay(index, failed, deadline)
        notes += [f"Cell {_name(self.nb.cells[i], i)} printed {n:,} characters; the grader kept the first "
                  f"{self.max_output_bytes:,}." for i, n in sorted(self._output_bytes.items()) if n > self.max_output_bytes]
        add_grader_notes(self.nb, notes)
        self.set_widgets_metadata()
        return self.nb, self.resources

    def _probe(self, cell: str) -> list:
        """The integrity monitor's findings so far, asked for after the graded cell ``cell``."""
        msg_id = self.kc.execute("", silent=True, store_history=False, user_expressions={PROBE_NAME: RUNTIME_PROBE})
        try:
            reply = self.wait_for_reply(msg_id)
        except (DeadKernelError, CellTimeoutError):
            reply = None
        result = reply["content"].get("user_expressions", {}).get(PROBE_NAME) if reply else None
        return runtime_findings(result, cell)

    def _restart_and_replay(self, upto: int, failed: set[int], deadline: float) -> None:
        """A fresh kernel that has silently run every code cell before ``upto`` that did not fail."""
        run_sync(self._async_restart)()
        for index, cell in enumerate(self.nb.cells[:upto]):
            if cell.cell_type != "code" or index in failed or time.monotonic() > deadline:
                continue
            msg_id = self.kc.execute(cell.source, silent=True, store_history=False, allow_stdin=False)
            try:
                reply = self.wait_for_reply(msg_id, cell)
            except (DeadKernelError, CellTimeoutError):
                reply = None
            if reply is None or reply["content"].get("ename") == TIMEOUT_ERROR:
                failed.add(index)
                run_sync(self._async_restart)()

    async def _async_restart(self) -> None:
        await self._async_cleanup_kernel()
        self.km = self.create_kernel_manager()
        await self.async_start_new_kernel()
        await self.async_start_new_kernel_client()

    def output(self, outs, msg, display_id, cell_index):
        """Keep at most ``max_output_bytes`` of text output per cell, then say that the rest was cut."""
        if msg["msg_type"] != "stream":
            return super().output(outs, msg, display_id, cell_index)
        used = self._output_bytes.get(cell_index, 0)
        text = msg["content"]["text"]
        self._output_bytes[cell_index] = used + len(text)
        if used >= self.max_output_bytes:
            return None
        if used + len(text) > self.max_output_bytes:
            msg = {**msg, "content": {**msg["content"], "text": text[: self.max_output_bytes - used]}}
            out = super().output(outs, msg, display_id, cell_index)
            outs.append(new_output("stream", name="stdout", text=(
                f"\n[The grader kept the first {self.max_output_bytes:,} characters of this cell's output "
                "and dropped the rest.]\n")))
            return out
        return super().output(outs, msg, display_id, cell_index)


def _name(cell: NotebookNode, index: int) -> str:
    """How a note names a cell: its nbgrader id, or its position."""
    return cells.grade_id(cell) if "grade_id" in cells.meta(cell) else str(index + 1)


def _add_error(cell: NotebookNode, ename: str, evalue: str) -> None:
    cell.outputs.append(new_output("error", ename=ename, evalue=evalue, traceback=[f"{ename}: {evalue}"]))

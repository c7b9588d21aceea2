"""The caps on each grading kernel that README promises (autograder/pipeline/execute.py, nbgrader_config.py):
their values, and the two ways a submission stops early, run on small notebooks with the grading
executor alone (no gradebook): the time limit for the whole submission, and too many restarts.

A stopped submission keeps the grades of the cells that ran; the cells after the stop get an error
that says why (so they score 0 when they are test cells), and the grader's note says it once.
"""

import nbformat
from nbclient import NotebookClient

from autograder.pipeline import nbgrader_apps
from autograder.pipeline.execute import NOT_RUN, GradingExecute
from autograder.pipeline.restore import grader_notes


def test_the_caps_are_readmes():
    """README: 4 GiB of address space, 30 s per cell, 300 s per submission, 1,000,000 characters of
    output kept per cell."""
    config = nbgrader_apps.course_config()
    executor = GradingExecute(config=config)
    assert (executor.memory_limit_gb, executor.timeout, executor.notebook_timeout, executor.max_output_bytes) == (
        4.0, 30, 300, 1_000_000)


def run(sources: list[str], tmp_path, **caps) -> nbformat.NotebookNode:
    """``sources`` as code cells, run by the grading executor with the course's configuration and
    ``caps`` in it (set in the configuration, which the executor re-reads for each notebook)."""
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(s) for s in sources])
    config = nbgrader_apps.course_config(tmp_path)
    for name, value in caps.items():
        setattr(config.GradingExecute, name, value)
    executor = GradingExecute(config=config)
    nb, _ = executor.preprocess(nb, {"metadata": {"path": str(tmp_path)}})
    return nb


def not_run(nb) -> list[int]:
    """The indices of the code cells that carry the grader's "not run" error."""
    return [i for i, c in enumerate(nb.cells) if c.cell_type == "code"
            and any(o.get("ename") == NOT_RUN for o in c.outputs)]


def test_a_submission_that_uses_up_its_time_is_stopped_and_told_once(tmp_path):
    """The first cell alone sleeps longer than the whole submission may take (2 s here, 300 s in the
    course), so every later cell is past the limit, however slowly the kernel started."""
    nb = run(["import time\ntime.sleep(3)", "a = 1", "b = 2", "c = 3"], tmp_path, notebook_timeout=2)
    code = [i for i, c in enumerate(nb.cells) if c.cell_type == "code"]
    stopped = not_run(nb)
    assert stopped and stopped == code[code.index(stopped[0]):] and stopped[-3:] == code[-3:], stopped
    for i in stopped:
        [error] = [o for o in nb.cells[i].outputs if o.output_type == "error"]
        assert error.evalue == "This cell was not run: the submission used up its time limit of 2 s."
    notes = [note.text for note in grader_notes(nb) if "were not run" in note.text]
    assert notes == [f"The cells from cell {stopped[0] + 1 - _offset(nb)} on were not run: the submission used up "
                     "its time limit of 2 s."], grader_notes(nb)


def _offset(nb) -> int:
    """How many cells the grader's note added at the top (a note names cells by their position)."""
    return 1 if grader_notes(nb) else 0


def test_a_kernel_restarted_too_often_stops_the_submission(tmp_path):
    """Three cells kill the kernel; with one restart allowed, the second death is the last one
    recovered from, and the cells after it are not run."""
    die = "import os\nos._exit(1)"
    nb = run([die, die, die, "d = 4"], tmp_path, max_restarts=1)
    offset = _offset(nb)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert [o.ename for o in code[0].outputs if o.output_type == "error"] == ["KernelDied"]
    assert [o.ename for o in code[1].outputs if o.output_type == "error"] == ["KernelDied"]
    assert not_run(nb) == [2 + offset, 3 + offset]
    notes = [note.text for note in grader_notes(nb)]
    assert notes == [
        "The kernel died in cell 1; it was restarted and the cells above it were run again.",
        "The kernel died in cell 2; it was restarted and the cells above it were run again.",
        "The cells from cell 3 on were not run: the kernel had to be restarted too often.",
    ], notes


def test_a_kernel_that_does_not_start_is_started_again(tmp_path, monkeypatch):
    """On a loaded machine a kernel once took more than nbclient's 180 s to answer, and nbgrader
    dropped the submission. Here the first start fails as nbclient fails it (the kernel is shut
    down, the error raised); the grader starts another, and the notebook runs in it."""
    starts = []
    start = NotebookClient.async_start_new_kernel_client

    async def first_start_fails(self):
        starts.append(self.km.kernel_id)
        if len(starts) == 1:
            self.kc = self.km.client()
            await self._async_cleanup_kernel()
            raise RuntimeError("Kernel didn't respond in 180 seconds")
        return await start(self)

    monkeypatch.setattr(NotebookClient, "async_start_new_kernel_client", first_start_fails)
    nb = run(["a = 6 * 7", "print(a)"], tmp_path)
    assert len(starts) == 2 and starts[0] != starts[1]
    assert nb.cells[1].outputs[0].text == "42\n", nb.cells[1].outputs


def test_a_kernel_that_never_starts_gives_up_after_the_attempts(tmp_path, monkeypatch):
    """Three starts (the course's setting), then nbclient's error reaches nbgrader, which reports the
    submission as not graded."""
    starts = []

    async def never_starts(self):
        starts.append(self.km.kernel_id)
        self.kc = self.km.client()
        await self._async_cleanup_kernel()
        raise RuntimeError("Kernel didn't respond in 180 seconds")

    monkeypatch.setattr(NotebookClient, "async_start_new_kernel_client", never_starts)
    try:
        run(["a = 1"], tmp_path)
    except RuntimeError as error:
        assert "didn't respond" in str(error)
    else:
        raise AssertionError("a kernel that never starts was not reported")
    assert len(starts) == 3 == len(set(starts))

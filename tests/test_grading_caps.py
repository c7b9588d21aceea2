"""The caps on each grading kernel that README promises (autograder/execute.py, nbgrader_config.py):
their values, and the two ways a submission stops early, run on small notebooks with the grading
executor alone (no gradebook): the time limit for the whole submission, and too many restarts.

A stopped submission keeps the grades of the cells that ran; the cells after the stop get an error
that says why (so they score 0 when they are test cells), and the grader's note says it once.
"""

import nbformat

from autograder import grading
from autograder.execute import NOT_RUN, GradingExecute
from autograder.restore_cells import grader_notes


def test_the_caps_are_readmes():
    """README: 4 GiB of address space, 30 s per cell, 300 s per submission, 1,000,000 characters of
    output kept per cell."""
    config = grading.course_config()
    executor = GradingExecute(config=config)
    assert (executor.memory_limit_gb, executor.timeout, executor.notebook_timeout, executor.max_output_bytes) == (
        4.0, 30, 300, 1_000_000)


def run(sources: list[str], tmp_path, **caps) -> nbformat.NotebookNode:
    """``sources`` as code cells, run by the grading executor with the course's configuration and
    ``caps`` in it (set in the configuration, which the executor re-reads for each notebook)."""
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(s) for s in sources])
    config = grading.course_config(tmp_path)
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
    notes = [note for note in grader_notes(nb) if "were not run" in note]
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
    notes = grader_notes(nb)
    assert notes == [
        "The kernel died in cell 1; it was restarted and the cells above it were run again.",
        "The kernel died in cell 2; it was restarted and the cells above it were run again.",
        "The cells from cell 3 on were not run: the kernel had to be restarted too often.",
    ], notes

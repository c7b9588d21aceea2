"""A catalogue of faulty submissions: what careless students hand in, and what grading must do.

Each fault builds a submission of a lab from its solved (or blank) notebook and says what grading
must make of it: which blanks lose their points (none, one, or all), and what the grades table
and the feedback must say. tests/test_faults.py grades them all in one batch with honest
submissions; the throughput benchmark mixes them into a class.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import nbformat
from nbformat import NotebookNode
from nbformat.v4 import new_code_cell

from autograder import cells
from autograder.catalogues import submissions
from autograder.labs import Lab

ALL = "all"


@dataclass(frozen=True)
class Fault:
    """A faulty submission, named ``slug``, whose blank ``target`` (if any) holds the fault."""

    slug: str
    what: str
    build: Callable[[Lab, str], tuple[str, bytes]]
    """(lab, blank) -> (file name, file contents)."""
    loses: str | None
    """None: nothing lost; "blank": only the faulty blank; ALL: every autograded cell."""
    says: str
    """Text that the grader's notes or the lost cell's reason must contain."""

    def student_id(self, lab: Lab) -> str:
        return f"{lab.id}_fault_{self.slug}"


def _file(lab: Lab, nb: NotebookNode, name: str | None = None) -> tuple[str, bytes]:
    return name or lab.notebook_name, nbformat.writes(nb).encode()


def _with_code_in_blank(lab: Lab, blank: str, code: str) -> tuple[str, bytes]:
    """The solved notebook with ``code`` run at the start of ``blank``'s body."""
    nb = submissions.solved(lab)
    source = cells.read(lab.source_notebook)
    [answer] = [c for c in source.cells if cells.is_code_answer(c) and cells.grade_id(c) == blank]
    lines = answer.source.splitlines()
    at = next(i for i, line in enumerate(lines) if line.strip() == cells.BEGIN_SOLUTION)
    indent = lines[at][: len(lines[at]) - len(lines[at].lstrip())]
    lines[at + 1 : at + 1] = [indent + line for line in code.splitlines()]
    faulty = copy.deepcopy(answer)
    faulty.source = "\n".join(lines)
    [cell] = [c for c in nb.cells if cells.is_code_answer(c) and cells.grade_id(c) == blank]
    cell.source = cells.model_answer(faulty)
    return _file(lab, nb)


def _line_before_blank(lab: Lab, blank: str) -> tuple[str, bytes]:
    """The solved notebook with a stray line that fails at the top of ``blank``'s cell, before its def."""
    nb = submissions.solved(lab)
    [cell] = [c for c in nb.cells if cells.is_code_answer(c) and cells.grade_id(c) == blank]
    cell.source = f"print(leftover_value)  # a line left over from an experiment\n{cell.source}"
    return _file(lab, nb)


def _solved_bytes(lab: Lab) -> bytes:
    return nbformat.writes(submissions.solved(lab)).encode()


def _reordered(lab: Lab, blank: str) -> tuple[str, bytes]:
    nb = submissions.solved(lab)
    nb.cells = nb.cells[::-1]
    return _file(lab, nb)


def _deleted(lab: Lab, blank: str) -> tuple[str, bytes]:
    nb = submissions.solved(lab)
    nb.cells = [c for c in nb.cells if not cells.meta(c).get("locked")]
    return _file(lab, nb)


def _loud_cell(lab: Lab, blank: str) -> tuple[str, bytes]:
    nb = submissions.solved(lab)
    nb.cells.insert(2, new_code_cell('print("x" * 100_000_000)  # a hundred megabytes'))
    return _file(lab, nb)


def _not_a_notebook(lab: Lab, blank: str) -> tuple[str, bytes]:
    return lab.notebook_name, b"I could not find the notebook, so here is my answer in words.\n"


def _truncated(lab: Lab, blank: str) -> tuple[str, bytes]:
    data = _solved_bytes(lab)
    return lab.notebook_name, data[: len(data) // 2]


def _empty(lab: Lab, blank: str) -> tuple[str, bytes]:
    return _file(lab, nbformat.v4.new_notebook())


def _hidden_markers(lab: Lab, blank: str) -> tuple[str, bytes]:
    nb = submissions.solved(lab)
    nb.cells.insert(2, new_code_cell(f"x = 1\n{cells.BEGIN_HIDDEN}\nprint('a test of my own')\n{cells.END_HIDDEN}"))
    return _file(lab, nb)


def _nbgrader_metadata(lab: Lab, blank: str) -> tuple[str, bytes]:
    """The solved notebook with one nbgrader flag or key changed in each of six cells: each alone made
    nbgrader 0.9.6 fail on the whole submission (the kind of edit a notebook tool or a JSON edit makes)."""
    nb = submissions.solved(lab)
    tests = [c for c in nb.cells if cells.is_autograded_test(c) and cells.grade_id(c) != f"test_{blank}"]
    answers = [c for c in nb.cells if cells.is_code_answer(c) and cells.grade_id(c) != blank]
    written = [c for c in nb.cells if c.cell_type == "markdown" and cells.meta(c).get("solution")]
    [test] = [c for c in nb.cells if cells.is_autograded_test(c) and cells.grade_id(c) == f"test_{blank}"]
    test.metadata["nbgrader"]["grade"] = False
    tests[0].metadata["nbgrader"]["solution"] = True
    tests[1].metadata["nbgrader"]["task"] = True
    tests[2].metadata["nbgrader"].update(score=1, kit_note="hi", comment="<b>x</b>")
    answers[0].metadata["nbgrader"].update(grade=True, points=5)
    written[0].metadata["nbgrader"]["grade"] = False
    return _file(lab, nb)


def _wrong_name(lab: Lab, blank: str) -> tuple[str, bytes]:
    return f"{lab.id} (1).ipynb", _solved_bytes(lab)


FAULTS = (
    Fault("not-json", "a file that is not a notebook at all", _not_a_notebook, ALL, "could not be read as a notebook"),
    Fault("truncated", "a notebook file cut off half-way", _truncated, ALL, "could not be read as a notebook"),
    Fault("empty", "a valid notebook with no cells", _empty, ALL, "put back as released"),
    Fault("wrong-name", "the solved notebook under another file name", _wrong_name, None, "submitted as"),
    Fault("reordered", "the solved notebook with its cells in reverse order", _reordered, None, "not in the lab's order"),
    Fault("deleted-cells", "the solved notebook without its set-up, check and test cells", _deleted, None,
          "put back as released"),
    Fault("nbgrader-metadata", "the solved notebook with nbgrader flags changed (a test cell that says grade: "
          "false, solution: true or task: true, an answer that says grade: true, a written answer that says grade: "
          "false, keys nbgrader does not know); each alone made nbgrader give up on the whole submission",
          _nbgrader_metadata, None, "was not as released"),
    Fault("infinite-loop", "a blank that never returns (while True: pass)",
          lambda lab, blank: _with_code_in_blank(lab, blank, "while True:\n    pass"), "blank", "CellTimeoutError"),
    Fault("sleep-loop", "a blank that sleeps in a loop and ignores interrupts",
          lambda lab, blank: _with_code_in_blank(
              lab, blank, "import time\nwhile True:\n    try:\n        time.sleep(0.5)\n    except KeyboardInterrupt:\n        pass"),
          "blank", "CellTimeoutError"),
    Fault("loud-cell", "a cell that prints 100 MB", _loud_cell, None, "the grader kept the first"),
    Fault("hidden-markers", "a cell of the student's own that holds the hidden-test markers around code of theirs "
          "(nbgrader gave up on the whole submission)", _hidden_markers, None, ""),
    Fault("kernel-dies", "a blank that kills its kernel (os._exit(1))",
          lambda lab, blank: _with_code_in_blank(lab, blank, "import os\nos._exit(1)"), "blank", "KernelDied"),
    Fault("memory-hog", "a blank that asks for 50 GB of memory",
          lambda lab, blank: _with_code_in_blank(lab, blank, "import numpy\n_ = numpy.ones(50 * 2**30 // 8)"),
          "blank", "MemoryError"),
    Fault("answer-cell-error", "a stray line at the top of a blank's cell that fails (a NameError) before the "
          "cell defines the blank, so that the blank is never defined", _line_before_blank, "blank",
          "failed when the grader ran it (NameError: name 'leftover_value' is not defined)"),
    Fault("numpy-warning", "a blank that is right but emits a NumPy warning",
          lambda lab, blank: _with_code_in_blank(lab, blank, "import numpy\n_ = numpy.log(-1.0)"),
          "blank", "gave the warning RuntimeWarning"),
)


def get(slug: str) -> Fault:
    """The catalogued fault called ``slug``."""
    [fault] = [f for f in FAULTS if f.slug == slug]
    return fault


def write_fault(fault: Fault, lab: Lab, blank: str, folder: Path) -> str:
    """Write ``fault`` in ``blank`` as a submission ``folder/<student>/<lab>/<file>``; the student id."""
    name, data = fault.build(lab, blank)
    path = folder / fault.student_id(lab) / lab.id / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(data)
    return fault.student_id(lab)


def write_faults(lab: Lab, blank: str, folder: Path) -> list[str]:
    """Write every fault as a submission ``folder/<student>/<lab>/<file>``; the student ids."""
    return [write_fault(fault, lab, blank, folder) for fault in FAULTS]

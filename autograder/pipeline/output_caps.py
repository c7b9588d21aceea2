"""How much output a graded submission keeps: a cap per cell and a cap for the whole notebook, and a cap
on each error's message.

``GradingExecute`` counts here, in characters, everything a submission's cells put out (printed
text, displayed data, results, and what the student's function printed during its hidden test). It
asks how much room a cell has left before it keeps an output; the first time a cell's output is cut,
the cell says so, and the grader's note names the cells that were cut. A hidden test keeps what the
student's function printed in a ``Capped`` stream, and each error's name, message and location is
``cut`` to MAX_MESSAGE_CHARS.
"""

from __future__ import annotations

import io
from collections.abc import Callable

from nbformat import NotebookNode
from nbformat.v4 import new_output

NOTED_LOUD_CELLS = 3
"""How many cells whose output was cut the grader's note names one by one (then it counts the rest)."""
MAX_MESSAGE_CHARS = 10_000
"""The most of an error's name, message or location that a test cell keeps."""


class OutputBudget:
    """The output counted and kept per cell (by index) and for the notebook."""

    def __init__(self, per_cell: int, per_notebook: int):
        self.per_cell = per_cell
        self.per_notebook = per_notebook
        self._put_out: dict[int, int] = {}
        self._kept: dict[int, int] = {}
        self._kept_total = 0

    def room(self, index: int) -> int:
        """How many more characters of output cell ``index`` may keep: within its own cap and the notebook's."""
        return max(0, min(self.per_cell - self._put_out.get(index, 0), self.per_notebook - self._kept_total))

    def count(self, cell: NotebookNode, index: int, size: int, kept: int) -> None:
        """Count ``size`` more characters of output of cell ``index``, of which it kept ``kept``; the
        first time some are dropped, the cell's output ends with a line that says so."""
        first_drop = kept < size and self._put_out.get(index, 0) <= self._kept.get(index, 0)
        self._put_out[index] = self._put_out.get(index, 0) + size
        self._kept[index] = self._kept.get(index, 0) + kept
        self._kept_total += kept
        if first_drop:
            cell.outputs.append(new_output("stream", name="stdout", text=(
                f"\n[The grader kept the first {self._kept[index]:,} characters of this cell's output and dropped "
                "the rest.]\n")))

    def notes(self, name: Callable[[int], str]) -> list[str]:
        """The grader's notes on the cells whose output was cut (``name`` names a cell by its index)."""
        loud = [i for i, n in sorted(self._put_out.items()) if n > self._kept.get(i, 0)]
        notes = [f"Cell {name(i)} printed {self._put_out[i]:,} characters; the grader kept the first "
                 f"{self._kept[i]:,}." for i in loud[:NOTED_LOUD_CELLS]]
        if len(loud) > NOTED_LOUD_CELLS:
            notes.append(f"{len(loud) - NOTED_LOUD_CELLS} more cells printed more than the grader keeps: "
                         f"{self.per_cell:,} characters of a cell's output, and {self.per_notebook:,} of the "
                         "whole notebook's.")
        return notes


class Capped(io.TextIOBase):
    """A text stream that keeps the first ``limit`` characters written to it, and counts them all."""

    def __init__(self, limit: int):
        super().__init__()
        self.limit, self.written, self.parts = limit, 0, []

    def writable(self) -> bool:
        return True

    def write(self, text: str) -> int:
        if self.written < self.limit:
            self.parts.append(text[: self.limit - self.written])
        self.written += len(text)
        return len(text)

    def getvalue(self) -> str:
        return "".join(self.parts)


def cut(text: str) -> str:
    """``text``, cut to MAX_MESSAGE_CHARS with a note that says so (an error's message, name or line)."""
    if len(text) <= MAX_MESSAGE_CHARS:
        return text
    dropped = len(text) - MAX_MESSAGE_CHARS
    return f"{text[:MAX_MESSAGE_CHARS]} [... {dropped:,} more characters cut by the grader]"


def error_output(ename: str, evalue: str, where: str = "") -> NotebookNode:
    """An error output as IPython's minimal traceback shows it: one line, plus where it was raised.
    Each part is cut to MAX_MESSAGE_CHARS: a student's exception can carry megabytes."""
    ename, evalue, where = (cut(text) for text in (ename, evalue, where))
    lines = [f"{ename}: {evalue}"] + ([f"(raised {where})"] if where else [])
    return new_output("error", ename=ename, evalue=evalue, traceback=lines)

"""Validate lists what to fix in the order you fix it: the code blanks first, then the written answers.

nbgrader's Validate (the button in JupyterLab, and ``nbgrader validate``) runs your notebook, then lists
each graded cell that fails in the notebook's order, so a written answer near the top (still "YOUR
ANSWER HERE") came before the code blanks that fail further down, and every empty written answer read
the same, without its question. The student bundle's ``jupyter_config/nbgrader_config.py`` calls
:func:`list_blanks_first`, which makes Validate, after it has run the notebook, list the graded code
cells first (each test cell names its blank, and its error is the first thing to fix), then the written
answers, each empty one shown by its question. Only Validate's copy of the notebook is reordered: your
file is not changed, and the cells run in their own order.
"""

from __future__ import annotations

import html
import re
from typing import Any

from nbformat import NotebookNode

QUESTION = re.compile(r"(?:\*\*|<strong>|<b>)((?:Question|Derivation|Written answer)[^*<]*)(?:\*\*|</strong>|</b>)\s*(.*)",
                      re.DOTALL)
"""A written answer's question: its bold lead ("Question 9 (0.5 points).") and the text after it, in Markdown
or, in a graded notebook whose Markdown the grader has rendered, in HTML."""
VALIDATED = re.compile(r"^validate\((\w+)\)", re.MULTILINE)
"""The line of a graded code cell that names its blank."""
SHOWN_CHARS = 160
"""How much of a question Validate shows for an empty answer."""


def _is_graded(cell: NotebookNode, cell_type: str) -> bool:
    nbgrader = cell.metadata.get("nbgrader", {})
    return cell.cell_type == cell_type and bool(nbgrader.get("grade"))


def question_of(nb: NotebookNode, index: int) -> str:
    """The question that the written answer ``nb.cells[index]`` answers: the bold lead of the text above
    it and its first sentence, on one line, at most SHOWN_CHARS long; its grade_id when there is none."""
    for cell in reversed(nb.cells[:index]):
        if cell.cell_type != "markdown" or cell.metadata.get("nbgrader", {}).get("solution"):
            continue
        found = list(QUESTION.finditer(cell.source))
        if not found:
            break
        lead = html.unescape(found[-1].group(1)).strip()
        rest = " ".join(html.unescape(re.sub(r"<[^>]*>", "", found[-1].group(2))).split())
        sentence = re.split(r"(?<=[.?])\s", rest, maxsplit=1)[0]
        text = f"{lead} {sentence}".strip()
        return text if len(text) <= SHOWN_CHARS else text[: SHOWN_CHARS - 3].rsplit(" ", 1)[0] + "..."
    return nb.cells[index].metadata.get("nbgrader", {}).get("grade_id", "a written answer")


SHOWN_ERROR_LINES = 8
"""The most lines of a failing graded cell's error that Validate shows: its first paragraph, which names the blank
and what to fix first (the notebook, under the cell, keeps the whole message)."""
MORE = "(The notebook shows the whole message under this cell and under its check cell.)"


def first_paragraph(traceback: list[str]) -> list[str]:
    """The lines of an error's first paragraph, at most SHOWN_ERROR_LINES, and a line that says where the rest is."""
    lines = "\n".join(traceback).split("\n")
    shown = []
    for line in lines:
        if not line.strip():
            break
        shown.append(line)
    shown = shown[:SHOWN_ERROR_LINES]
    return shown + [MORE] if len(shown) < len([line for line in lines if line.strip()]) else shown


def ordered_for_validate(nb: NotebookNode) -> NotebookNode:
    """``nb`` (Validate's executed copy) with its graded code cells first, then its written answers, then
    the rest, each group in its own order. An empty written answer (its checksum unchanged, which is how
    nbgrader tells) is shown by its question, and keeps counting as empty. A graded code cell that fails is
    shown by its blank and points, not its source (a student review: its comment, "Hidden tests of ...",
    read as if the hidden tests had run), and with the first paragraph of its error (a student review: Validate printed each message whole, with
    the cell's source); a graded cell that a student changed keeps its source, so that Validate says so."""
    from nbgrader.utils import compute_checksum

    for index, cell in enumerate(nb.cells):
        nbgrader = cell.metadata.get("nbgrader", {})
        if _is_graded(cell, "markdown") and nbgrader.get("checksum") == compute_checksum(cell):
            cell.source = question_of(nb, index)  # nbgrader adds "You did not provide a response."
            nbgrader["checksum"] = compute_checksum(cell)
        errors = [o for o in cell.get("outputs", []) if o.get("output_type") == "error"]
        if _is_graded(cell, "code") and errors and nbgrader.get("checksum") == compute_checksum(cell):
            for error in errors:
                error["traceback"] = first_paragraph(error.get("traceback", []))
            blank = VALIDATED.search(cell.source)
            if blank is not None:
                points = nbgrader.get("points", 0)
                cell.source = (f"The graded cell of {blank.group(1)} ({points:g} point{'s' if points != 1 else ''}).\n"
                               "Validate runs its visible checks only; its hidden tests run when you are graded.")
                nbgrader["checksum"] = compute_checksum(cell)
    rank = [0 if _is_graded(c, "code") else 1 if _is_graded(c, "markdown") else 2 for c in nb.cells]
    nb.cells = [cell for _, _, cell in sorted(zip(rank, range(len(nb.cells)), nb.cells), key=lambda t: t[:2])]
    return nb


def list_blanks_first() -> None:
    """Make nbgrader's Validator order its copy of the notebook with :func:`ordered_for_validate` once it has
    run it. Does nothing if this nbgrader has no such step (Validate then keeps nbgrader's own order;
    tests/test_validate.py fails on such an nbgrader)."""
    from nbgrader.validator import Validator

    run = getattr(Validator, "_preprocess", None)
    if run is None or getattr(run, "lists_blanks_first", False):
        return

    def run_then_order(self: Any, nb: NotebookNode) -> NotebookNode:
        return ordered_for_validate(run(self, nb))

    run_then_order.lists_blanks_first = True  # type: ignore[attr-defined]
    Validator._preprocess = run_then_order

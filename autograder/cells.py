"""Reading nbgrader cells: answer cells, test cells, and the model answers in a source notebook."""

from __future__ import annotations

import ast
from pathlib import Path

import nbformat
from nbformat import NotebookNode

BEGIN_SOLUTION = "### BEGIN SOLUTION"
END_SOLUTION = "### END SOLUTION"
BEGIN_HIDDEN = "### BEGIN HIDDEN TESTS"
END_HIDDEN = "### END HIDDEN TESTS"


def read(path: Path) -> NotebookNode:
    return nbformat.read(path, as_version=4)


def meta(cell: NotebookNode) -> dict:
    return cell.metadata.get("nbgrader", {})


def is_answer(cell: NotebookNode) -> bool:
    """A cell the student writes in (code blank or written answer)."""
    return bool(meta(cell).get("solution"))


def is_code_answer(cell: NotebookNode) -> bool:
    """A blank: an autograded answer cell that defines one function."""
    return is_answer(cell) and cell.cell_type == "code" and not meta(cell).get("grade")


def is_autograded_test(cell: NotebookNode) -> bool:
    return bool(meta(cell).get("grade")) and not meta(cell).get("solution") and cell.cell_type == "code"


CHECK_PREFIX = "check_"
"""The grade id of a blank's visible check cell is this prefix and the blank's name."""


def is_visible_check(cell: NotebookNode) -> bool:
    """A blank's visible check cell: a locked, ungraded code cell whose grade id is ``check_<blank>``
    (it ends with ``passed("<blank>")``)."""
    return (cell.cell_type == "code" and not meta(cell).get("grade") and not meta(cell).get("solution")
            and str(meta(cell).get("grade_id", "")).startswith(CHECK_PREFIX))


def grade_id(cell: NotebookNode) -> str:
    return meta(cell)["grade_id"]


def model_answer(cell: NotebookNode) -> str:
    """An answer cell's source with the solution delimiters removed: what a perfect student writes."""
    lines = cell.source.splitlines()
    return "\n".join(line for line in lines if line.strip() not in (BEGIN_SOLUTION, END_SOLUTION))


def model_answers(source_nb: NotebookNode) -> dict[str, str]:
    """grade_id -> model answer, for every answer cell of a source notebook."""
    return {grade_id(cell): model_answer(cell) for cell in source_nb.cells if is_answer(cell)}


def defined_functions(code: str) -> list[ast.FunctionDef]:
    """The top-level functions that a piece of code (IPython magics removed) defines."""
    lines = [line for line in code.splitlines() if not line.lstrip().startswith(("%", "!"))]
    return [node for node in ast.parse("\n".join(lines)).body if isinstance(node, ast.FunctionDef)]


def blank_names(source_nb: NotebookNode) -> list[str]:
    """The names of the functions that the blanks of a source notebook define."""
    return [f.name for cell in source_nb.cells if is_code_answer(cell) for f in defined_functions(cell.source)]

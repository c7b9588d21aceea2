"""Synthetic submissions: the blank release notebook, the solved one, and one per catalogued mistake."""

from __future__ import annotations

import copy
import shutil
from pathlib import Path

import nbformat
from nbformat import NotebookNode

from autograder import cells
from autograder.labs import Lab
from autograder.catalogues.mistakes import Mistake, catalogue

SOLVED = "solved"
BLANK = "blank"


def solved(lab: Lab) -> NotebookNode:
    """The release notebook with every answer cell filled in with its model answer."""
    answers = cells.model_answers(cells.read(lab.source_notebook))
    nb = cells.read(lab.release_notebook)
    for cell in nb.cells:
        if cells.is_answer(cell):
            cell.source = answers[cells.grade_id(cell)]
    return nb


def with_mistake(lab: Lab, mistake: Mistake) -> NotebookNode:
    """The solved notebook with one mistake made in the answer cell of ``mistake.blank``."""
    nb = copy.deepcopy(solved(lab))
    [cell] = [c for c in nb.cells if cells.is_code_answer(c) and cells.grade_id(c) == mistake.blank]
    cell.source = mistake.apply(cell.source)
    return nb


def write(nb: NotebookNode, folder: Path, student: str, lab: Lab) -> Path:
    """Write ``nb`` as ``student``'s submission of ``lab``: ``folder/<student>/<lab>/<lab>.ipynb``."""
    path = folder / student / lab.id / lab.notebook_name
    path.parent.mkdir(parents=True, exist_ok=True)
    nbformat.write(nb, path)
    return path


def write_class(labs: list[Lab], folder: Path) -> list[str]:
    """Write a demo class as ``folder/<student>/<lab>/<lab>.ipynb`` and return the student ids.

    Student ``blank`` submits every release notebook unchanged, ``solved`` every model answer,
    and each catalogued mistake is a student of its own who submits one lab.
    """
    if folder.exists():
        shutil.rmtree(folder)
    submissions: list[tuple[str, Lab, NotebookNode]] = []
    for lab in labs:
        submissions.append((BLANK, lab, cells.read(lab.release_notebook)))
        submissions.append((SOLVED, lab, solved(lab)))
        submissions += [(m.student_id(lab), lab, with_mistake(lab, m)) for m in catalogue(lab)]
    for student, lab, nb in submissions:
        write(nb, folder, student, lab)
    return sorted({student for student, _, _ in submissions})

"""Synthetic submissions: the blank release notebook, the solved one, and one per catalogued mistake
or one per group of catalogued mistakes in different blanks."""

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
    return with_mistakes(lab, [mistake])


def with_mistakes(lab: Lab, mistakes: list[Mistake]) -> NotebookNode:
    """The solved notebook with each mistake made in the answer cell of its blank (one per blank)."""
    assert len({m.blank for m in mistakes}) == len(mistakes), "two mistakes in one blank"
    nb = copy.deepcopy(solved(lab))
    for mistake in mistakes:
        [cell] = [c for c in nb.cells if cells.is_code_answer(c) and cells.grade_id(c) == mistake.blank]
        cell.source = mistake.apply(cell.source)
    return nb


def mistake_groups(lab: Lab) -> dict[str, list[Mistake]]:
    """Every catalogued mistake of ``lab`` in exactly one group, as few groups as can be: student id ->
    its mistakes. No two mistakes of a group are in one blank, and a group's blanks are every other
    blank of those that have mistakes (the first, third, ... or the second, fourth, ...), so that a
    submission of a group also holds correct blanks that must keep their marks beside the wrong ones."""
    mistaken = [b for b in cells.blank_names(cells.read(lab.source_notebook)) if any(m.blank == b for m in catalogue(lab))]
    groups: dict[str, list[Mistake]] = {}
    for parity, name in ((0, "odd"), (1, "even")):
        per_blank = [[m for m in catalogue(lab) if m.blank == blank] for blank in mistaken[parity::2]]
        for k in range(max(map(len, per_blank), default=0)):
            groups[f"{lab.id}_mistakes-{name}-{k + 1}"] = [ms[k] for ms in per_blank if k < len(ms)]
    return groups


def write(nb: NotebookNode, folder: Path, student: str, lab: Lab) -> Path:
    """Write ``nb`` as ``student``'s submission of ``lab``: ``folder/<student>/<lab>/<lab>.ipynb``."""
    path = folder / student / lab.id / lab.notebook_name
    path.parent.mkdir(parents=True, exist_ok=True)
    nbformat.write(nb, path)
    return path


def write_class(labs: list[Lab], folder: Path, grouped: bool = False) -> list[str]:
    """Write a demo class as ``folder/<student>/<lab>/<lab>.ipynb`` and return the student ids.

    Student ``blank`` submits every release notebook unchanged, ``solved`` every model answer,
    and each catalogued mistake is a student of its own who submits one lab; with ``grouped``, each
    group of ``mistake_groups`` is (every mistake graded, in a third as many submissions).
    """
    if folder.exists():
        shutil.rmtree(folder)
    students = set()
    for lab in labs:
        wrong = mistake_groups(lab).items() if grouped else [(m.student_id(lab), [m]) for m in catalogue(lab)]
        submissions = [(BLANK, cells.read(lab.release_notebook)), (SOLVED, solved(lab))]
        submissions += [(student, with_mistakes(lab, mistakes)) for student, mistakes in wrong]
        for student, nb in submissions:
            write(nb, folder, student, lab)
            students.add(student)
    return sorted(students)

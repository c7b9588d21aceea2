"""``python -m autograder build <lab>``: the lab's source notebook from its draft, run, released and listed.

The draft, ``solutions/<module>/draft.py``, is the notebook as text in jupytext's percent format: each
cell starts with a ``# %%`` line, which carries the cell's nbgrader metadata as
``nbgrader={"grade_id": ..., ...}`` (``grade``, ``locked``, ``solution`` and ``task`` default to false,
``schema_version`` to 3), and Markdown cells start with ``# %% [markdown]``.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import jupytext
import nbformat
from nbclient import NotebookClient
from nbformat import NotebookNode
from nbgrader.nbgraderformat import MetadataValidator

from autograder import cells
from autograder.authoring import consistency
from autograder.authoring.inventory import print_inventory
from autograder.labs import ROOT, Lab
from autograder.release import data
from autograder.release.notebooks import release_all
from course.checks import count

KERNELSPEC = {"display_name": "Python 3 (ipykernel)", "language": "python", "name": "python3"}
NBGRADER_DEFAULTS = {"grade": False, "locked": False, "schema_version": 3, "solution": False, "task": False}
LAYOUT_METADATA = ("lines_to_next_cell", "lines_to_end_of_cell_marker")
"""Cell metadata that jupytext keeps only to lay the draft out again; not part of the notebook."""
CELL_TIMEOUT_S = 120
CELL_MARKER = re.compile(r"^# %%", re.MULTILINE)


def notebook_from_draft(draft: Path) -> NotebookNode:
    """The notebook a draft describes, without outputs: kernelspec python3, nbgrader schema-3 metadata,
    and each cell's id its grade_id with hyphens (``cell-<index>`` for a cell without one).

    Raises nbgrader's ValidationError if the draft's nbgrader metadata are not valid.
    """
    nb = jupytext.read(draft, fmt="py:percent")
    nb.metadata = nbformat.from_dict({"kernelspec": KERNELSPEC})
    for index, cell in enumerate(nb.cells):
        for key in LAYOUT_METADATA:
            cell.metadata.pop(key, None)
        if "nbgrader" in cell.metadata:
            cell.metadata.nbgrader = nbformat.from_dict({**NBGRADER_DEFAULTS, **cell.metadata.nbgrader})
            cell.id = cells.grade_id(cell).replace("_", "-")
        else:
            cell.id = f"cell-{index}"
    MetadataValidator().validate_nb(nb)
    return nb


def _described(cell: NotebookNode) -> tuple[str, str, str, dict]:
    return cell.id, cell.cell_type, cell.source, dict(cell.metadata.get("nbgrader", {}))


def draft_differences(draft: Path, notebook: NotebookNode) -> list[str]:
    """Where ``notebook`` differs from the one its draft describes, outputs aside: the kernel, the list
    of cells, and each cell (by id) whose type, source or nbgrader metadata differ. None: they agree."""
    made = notebook_from_draft(draft)
    found = [] if notebook.metadata.get("kernelspec", {}).get("name") == KERNELSPEC["name"] else ["the kernel is not python3"]
    if [c.id for c in made.cells] != [c.id for c in notebook.cells]:
        return [*found, f"the draft has the cells {[c.id for c in made.cells]}, the notebook {[c.id for c in notebook.cells]}"]
    return found + [f"cell {m.id} differs" for m, n in zip(made.cells, notebook.cells) if _described(m) != _described(n)]


def _names(nb: NotebookNode, draft: Path) -> list[str]:
    """Each cell's name in a message: its line in the draft (where its ``# %%`` line is) and its
    grade_id, or its index for a cell without one."""
    text = draft.read_text()
    lines = [f"line {text.count(chr(10), 0, match.start()) + 1}, " for match in CELL_MARKER.finditer(text)]
    if len(lines) != len(nb.cells):  # a first cell without its marker: lines unknown
        lines = [""] * len(nb.cells)
    return [f"{line}cell {cells.grade_id(cell) if 'nbgrader' in cell.metadata else index}"
            for index, (line, cell) in enumerate(zip(lines, nb.cells))]


def execute(nb: NotebookNode, folder: Path) -> list[tuple[int, str]]:
    """Run every cell of ``nb`` in place, in a python3 kernel started in ``folder`` with the course root on
    PYTHONPATH (as nbval runs the source notebooks); return (index, what went wrong) of each cell that
    raised an error or wrote to stderr (nbgrader gives 0 to a test cell that does).

    Not the grader's way of starting a kernel (``SandboxedKernelManager``, autograder/kernel/manager.py),
    and it cannot be: a source notebook's hidden blocks run here as written, importing ``solutions`` in the
    kernel, and the grading sandbox refuses a kernel that can read the course root (rule 10). Both kernels
    import this root's ``course`` all the same: each has it first on its path, ahead of the environment's
    ``-e .`` (here the root on PYTHONPATH; in grading ``manager.course_site()``, this root's ``course/``
    alone), which tests/test_sandbox.py checks. One way for both would need ``build`` to run the notebook as
    grading does (GradingExecute: the hidden blocks run in the build's process against the kernel, with
    nbgrader's resources and a grading secret) and store that run's outputs in source/."""
    NotebookClient(nb, timeout=CELL_TIMEOUT_S, kernel_name=KERNELSPEC["name"], allow_errors=True,
                   resources={"metadata": {"path": str(folder)}}).execute(env={**os.environ, "PYTHONPATH": str(ROOT)})
    problems = []
    for index, cell in enumerate(nb.cells):
        for output in cell.get("outputs", []):
            if output.output_type == "error":
                problems.append((index, f"{output.ename}: {output.evalue}"))
            elif output.output_type == "stream" and output.name == "stderr":
                problems.append((index, f"wrote to stderr: {output.text.strip()}"))
    return problems


def build_lab(lab: Lab, keep_data: bool = False) -> bool:
    """Make ``source/<lab>/<lab>.ipynb`` from the lab's draft (after rebuilding its shipped data, if it
    ships any and ``keep_data`` is false), run it in place and save it; if no cell failed, release it (``release/<lab>/``, with the
    leak check) and print its inventory. Prints each cell that failed, by its line in the draft and its
    grade_id, with the error; returns whether the build succeeded."""
    if not lab.draft.exists():
        raise FileNotFoundError(f"{lab.id} has no draft, {lab.draft.relative_to(ROOT)}: `jupytext --to py:percent "
                                f"{lab.source_notebook.relative_to(ROOT)} -o {lab.draft.relative_to(ROOT)}` makes one from "
                                "its notebook (docs/adding-a-lab.md).")
    nb = notebook_from_draft(lab.draft)
    if data.ships_data(lab) and keep_data:
        print(f"kept {lab.id}'s shipped data as they are; `python -m autograder data --check` tells whether a rebuild "
              "reproduces them")
    elif data.ships_data(lab):
        for path in data.rebuild([lab]):
            print(f"wrote {path.relative_to(ROOT)}")
    lab.source_notebook.parent.mkdir(parents=True, exist_ok=True)
    nbformat.write(nb, lab.source_notebook)  # first unrun: the hidden tests read the lab's blanks from it
    problems = execute(nb, lab.source_notebook.parent)
    nbformat.write(nb, lab.source_notebook)
    print(f"wrote {lab.source_notebook.relative_to(ROOT)}, run")
    if problems:
        names = _names(nb, lab.draft)
        print(f"{count(len(problems), 'problem')} in the cells of {lab.draft.relative_to(ROOT)}; fix the draft and "
              "build again (the notebook keeps the tracebacks):")
        for index, problem in problems:
            print(f"  {names[index]}: {problem}")
        return False
    problems = [*consistency.answers_unlike_reference(lab, nb), *(
        f"{where} stays TeX on the feedback page: a line inside $...$ that begins with +, -, * or a number and a "
        "full stop starts a Markdown list; break the line elsewhere" for where in consistency.formulas_left_as_text(nb)),
        *consistency.summary_disagrees(nb)]
    if problems:
        print(f"{count(len(problems), 'problem')} in {lab.draft.relative_to(ROOT)} or its reference; fix them and build again:")
        for problem in problems:
            print(f"  {problem}")
        return False
    release_all([lab])
    print(f"released to {lab.release_notebook.relative_to(ROOT)}; no leaks found\n")
    print_inventory([lab])
    return True

"""The feedback pages: what nbgrader's feedback shows, and three things it does not.

- A written answer that nobody has graded yet says "not graded yet", not "0 / 2".
- A test cell that earned its marks although the visible check above it failed says why: the
  check ran the student's other blanks, the hidden tests graded this blank with the reference's.
- Long messages wrap (the template's CSS).
- The page opens with a summary (``summary``): points earned of the total, how many blanks earned
  full marks, the written answers not graded yet, and a link to the first cell that lost points.
- Its TeX is MathML, made here (autograder.pipeline.mathml): the page loads no MathJax, no script.

``FeedbackGrades`` (nbgrader's GetGrades, extended) marks the cells; the template
``templates/kit_feedback`` shows them. ``regenerate`` rewrites every feedback page and the grades
CSV from the gradebook after written answers were graded by hand in formgrader.
"""

from __future__ import annotations

import ast
import re
from functools import cache
from pathlib import Path

import nbgrader
from nbformat import NotebookNode
from nbgrader.preprocessors import GetGrades

from autograder import cells
from autograder.labs import Lab
from autograder.pipeline import mathml
from course.checks import listed
from course.validate_order import question_of

TEMPLATES = Path(__file__).resolve().parent / "templates"
"""The kit's nbconvert templates."""
TEMPLATE = "kit_feedback"
"""The feedback template, which extends nbgrader's."""
NBGRADER_TEMPLATES = Path(nbgrader.__file__).resolve().parent / "server_extensions" / "formgrader" / "templates"
"""Where nbgrader keeps its feedback template (``feedback/index.html.j2``, which ours extends)."""
TEMPLATE_PATHS = [str(NBGRADER_TEMPLATES.parent / "static" / "node_modules" / "bootstrap" / "dist" / "css"), str(NBGRADER_TEMPLATES)]
"""Where the feedback template finds nbgrader's CSS (as GenerateFeedback sets it) and nbgrader's template."""


def _names_in(source: str) -> set[str]:
    """The names a cell's code uses (IPython magics and shell lines left out)."""
    code = "\n".join(line for line in source.splitlines() if not line.lstrip().startswith(("%", "!")))
    try:
        return {node.id for node in ast.walk(ast.parse(code)) if isinstance(node, ast.Name)}
    except SyntaxError:
        return set(re.findall(r"[A-Za-z_]\w*", code))


def _failed(cell: NotebookNode) -> bool:
    return cell.cell_type == "code" and any(o.output_type == "error" for o in cell.get("outputs", []))


def cross_blank_note(blank: str, others_lost: list[str]) -> str:
    """What a test cell with full marks says when the visible check of its blank failed."""
    if others_lost:
        named = listed(others_lost)
        verb = "loses its" if len(others_lost) == 1 else "lose their"
        cause = (f"That check also ran your {named}, which {verb} marks in this notebook, "
                 "so fix that first: this check should then pass too.")
    else:
        cause = "That check ran your code with the other blanks as you wrote them; read its message above."
    return (f"The visible check of {blank} above failed, yet {blank} earns full marks here: the hidden tests "
            f"grade each blank on its own, with the reference in place of every other blank. {cause}")


def _points(cell: NotebookNode) -> tuple[float, float]:
    """(score, points) of a graded cell."""
    return float(cell.metadata.nbgrader.get("score") or 0), float(cell.metadata.nbgrader.get("points") or 0)


def _is_blank(cell: NotebookNode) -> bool:
    """A blank's graded test cell (``test_<blank>``)."""
    return cells.is_autograded_test(cell) and cells.grade_id(cell).startswith("test_")


def summary(nb: NotebookNode) -> dict:
    """What the page says first: the blanks (test cells ``test_<blank>``) and how many earned full
    marks, their points, the written answers not graded yet, and the first graded cell, in the
    notebook's order, that lost points (``first_lost``: its grade id, name, score and points; None
    if none did). Run after GetGrades has scored the cells."""
    graded = [c for c in nb.cells if cells.meta(c).get("grade")]
    blanks = [c for c in graded if _is_blank(c)]
    waiting = [c for c in graded if c.metadata.nbgrader.get("needs_manual_grade")]
    lost = [c for c in graded if c not in waiting and _points(c)[0] < _points(c)[1]]
    first = lost[0] if lost else None
    return {
        "blanks": len(blanks),
        "blanks_full": sum(_points(c)[0] >= _points(c)[1] for c in blanks),
        "blank_score": sum(_points(c)[0] for c in blanks),
        "blank_points": sum(_points(c)[1] for c in blanks),
        "written_waiting": len(waiting),
        "first_lost": first and {
            "grade_id": cells.grade_id(first),
            "name": cells.grade_id(first).removeprefix("test_") if _is_blank(first)
            else first.metadata.nbgrader.get("kit_question") or cells.grade_id(first),
            "blank": _is_blank(first),
            "score": _points(first)[0], "points": _points(first)[1]},
    }


@cache
def _questions(lab_id: str) -> dict[str, str]:
    """Each written answer's question, as the lab releases it: grade_id -> question. Not the submission's text above
    the answer, which is the student's to edit (an adversarial review of issue 36: a student's text stood in the
    page's summary as the question)."""
    released = cells.read(Lab(lab_id).release_notebook)
    return {cells.grade_id(cell): question_of(released, index) for index, cell in enumerate(released.cells)
            if cell.cell_type == "markdown" and cells.meta(cell).get("grade")}


class FeedbackGrades(GetGrades):
    """nbgrader's GetGrades, which also marks written answers not graded yet (``needs_manual_grade``),
    totals their points (``resources['nbgrader']['ungraded_points']``), notes at a test cell
    with full marks whose blank's visible check failed (``kit_note``), gives each written answer
    its question (``kit_question``), which names it in the page's list of contents, and puts the
    page's ``summary`` in ``resources['nbgrader']['kit_summary']``. It starts the page's budget of
    TeX conversion (``mathml.start_page``): it runs once per page, before the template."""

    def _get_score(self, cell: NotebookNode, resources: dict) -> None:
        super()._get_score(cell, resources)
        grade = self.gradebook.find_grade(cell.metadata["nbgrader"]["grade_id"], self.notebook_id,
                                          self.assignment_id, self.student_id)
        cell.metadata.nbgrader["needs_manual_grade"] = bool(grade.needs_manual_grade)

    def preprocess(self, nb: NotebookNode, resources: dict) -> tuple[NotebookNode, dict]:
        mathml.start_page()
        nb, resources = super().preprocess(nb, resources)
        graded = [c for c in nb.cells if cells.meta(c).get("grade")]
        resources["nbgrader"]["ungraded_points"] = sum(
            c.metadata.nbgrader.get("points") or 0 for c in graded if c.metadata.nbgrader.get("needs_manual_grade"))
        questions = _questions(resources["nbgrader"]["assignment"])
        for cell in nb.cells:
            if cell.cell_type == "markdown" and cells.meta(cell).get("grade"):
                # the contents list names each written answer by its question, not "Written response" each time
                cell.metadata.nbgrader["kit_question"] = questions.get(cells.grade_id(cell), cells.grade_id(cell))
        tests = {cells.grade_id(c).removeprefix("test_"): c for c in graded if cells.grade_id(c).startswith("test_")}
        lost = [blank for blank, c in tests.items()
                if (c.metadata.nbgrader.get("score") or 0) < c.metadata.nbgrader.get("points", 0)]
        for cell in nb.cells:
            grade_id = cells.meta(cell).get("grade_id", "")
            blank = grade_id.removeprefix("check_")
            test = tests.get(blank) if grade_id.startswith("check_") else None
            if test is None or not _failed(cell) or blank in lost:
                continue
            uses = _names_in(cell.source)
            test.metadata.nbgrader["kit_note"] = cross_blank_note(blank, [b for b in lost if b != blank and b in uses])
        resources["nbgrader"]["kit_summary"] = summary(nb)
        return nb, resources


def regenerate(workdir: Path, out_csv: Path | None = None) -> list:
    """Rewrite every feedback page in ``workdir/feedback/`` and the grades CSV (default
    ``workdir/grades.csv``) from the gradebook, without grading anything again: run it after
    grading written answers in formgrader. Returns the grade rows."""
    from nbgrader.converters import GenerateFeedback

    from autograder.pipeline import grades, nbgrader_apps

    labs = grades.all_graded_labs(workdir)
    for lab in labs:
        nbgrader_apps.run_checked(GenerateFeedback, workdir, lab)
    rows = grades.read_grades(workdir, labs)
    grades.write_grades(rows, out_csv or workdir / "grades.csv")
    return rows

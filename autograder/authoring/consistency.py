"""What ``build`` checks in a lab's notebook beyond running it: each model answer is its reference's
function, and every formula of its Markdown becomes math on the feedback page."""

from __future__ import annotations

import ast
import re
import inspect
from html.parser import HTMLParser

from nbformat import NotebookNode

from autograder import cells
from autograder.labs import Lab
from autograder.pipeline import mathml
from autograder.pipeline.inert_html import inert_markdown, rendered
from autograder.pipeline.sanitise import sanitise_math


def without_docstring(func: ast.FunctionDef) -> str:
    """A function's body, its docstring left out, as an AST dump (for comparing two functions' code)."""
    body = func.body
    if isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) and isinstance(body[0].value.value, str):
        body = body[1:]
    return ast.dump(ast.Module(body=body, type_ignores=[]), annotate_fields=False)


def answers_unlike_reference(lab: Lab, nb: NotebookNode) -> list[str]:
    """For each answer cell whose model answer is not the code of the reference's function of its name
    (docstrings aside), a sentence that says so: the hidden tests and the mutants read the reference."""
    reference = lab.reference()
    differ = []
    for cell in (c for c in nb.cells if cells.is_code_answer(c)):
        name = cells.grade_id(cell)
        ours = getattr(reference, name, None)
        if ours is None:
            differ.append(f"{name}: solutions/{lab.module}/reference.py has no function {name}")
            continue
        answer = ast.parse(cells.model_answer(cell)).body[0]
        if without_docstring(answer) != without_docstring(ast.parse(inspect.getsource(ours)).body[0]):
            differ.append(f"{name}: the model answer in the notebook differs from solutions/{lab.module}/reference.py's "
                          f"{name}; make them the same code (docstrings may differ)")
    return differ


def feedback_page_markup(markdown: str) -> str:
    """What the feedback page makes of a Markdown cell: InertHtml, as grading runs it, then the
    template's Markdown and its sanitiser, formulas as MathML."""
    cell = NotebookNode(cell_type="markdown", source=markdown, metadata={})
    inert_markdown(cell)
    mathml.start_page()
    return sanitise_math(rendered(cell.source))


class _PageText(HTMLParser):
    """The text of a page, its tags left out."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.parts: list[str] = []

    def handle_data(self, data: str) -> None:
        self.parts.append(data)


def formulas_left_as_text(nb: NotebookNode) -> list[str]:
    """Each formula of the notebook's Markdown that the feedback page would show as TeX, not math, with
    its cell's number. The usual cause: a wrapped line inside ``$...$`` that begins with ``+``, ``-``,
    ``*`` or a number and a full stop, which Markdown reads as a list item, splitting the formula."""
    left = []
    for index, cell in enumerate(nb.cells):
        if cell.cell_type == "markdown":
            text = _PageText()
            text.feed(feedback_page_markup(cell.source))
            text.close()
            left += [f"cell {index}: {found.group(0)[:80]}" for found in mathml.FORMULA.finditer("".join(text.parts))]
    return left


SECTION = re.compile(r"^##\s+(\d+)\.", re.MULTILINE)
GOING_FURTHER = re.compile(r"^##\s+(\d+\.\s*)?Going further", re.MULTILINE)
ROW_SECTIONS = re.compile(r"^\s*\**\s*(\d+)(?:\s*[–-]\s*(\d+))?((?:\s*,\s*\d+)*)")


def _graded_by_section(nb: NotebookNode) -> tuple[dict[int, float], dict[int, set[str]], list[str]]:
    """Points of the graded cells and names of the code blanks in each numbered section ("## N."), and
    the grade_ids of graded cells after a "Going further" heading."""
    points: dict[int, float] = {}
    blanks: dict[int, set[str]] = {}
    beyond: list[str] = []
    section, further = 0, False
    for cell in nb.cells:
        if cell.cell_type == "markdown" and not cells.meta(cell).get("solution"):
            if found := SECTION.search(cell.source):
                section = int(found.group(1))
            further = further or bool(GOING_FURTHER.search(cell.source))
        if cells.is_code_answer(cell):
            blanks.setdefault(section, set()).add(cells.grade_id(cell))
        if cell_points := cells.meta(cell).get("points"):
            points[section] = points.get(section, 0) + cell_points
            if further:
                beyond.append(cells.grade_id(cell))
    return points, blanks, beyond


def _summary_rows(first: str) -> list[list[str]] | None:
    """The rows (header first, the |---| line left out) of the first Markdown table in ``first`` whose
    header has a "points" column, or None."""
    rows: list[list[str]] = []
    for line in first.splitlines() + [""]:
        if line.lstrip().startswith("|"):
            row = [part.strip() for part in line.strip().strip("|").split("|")]
            if not all(re.fullmatch(r":?-+:?", part) for part in row):
                rows.append(row)
        elif rows:
            if any(head.lower() == "points" for head in rows[0]):
                return rows
            rows = []
    return None


def _row_sections(label: str) -> list[int]:
    """The section numbers a row's first column names: "3.", "3–4" or "8, 9" (none for the total row)."""
    found = ROW_SECTIONS.match(label)
    if not found:
        return []
    first, last, more = found.groups()
    numbers = list(range(int(first), int(last or first) + 1))
    return numbers + [int(n) for n in re.findall(r"\d+", more or "")]


def summary_disagrees(nb: NotebookNode) -> list[str]:
    """Where the first cell's table of what is graded disagrees with the notebook: each row names
    sections ("3.", "3–4"), the code blanks in them (in backticks) and their points; the last row
    ("all") the total. Also each graded cell after a "Going further" heading, which must hold none."""
    points, blanks, beyond = _graded_by_section(nb)
    problems = [f"{name} is graded but comes after the \"Going further\" heading; that part is not graded"
                for name in beyond]
    rows = _summary_rows(nb.cells[0].source) if nb.cells and nb.cells[0].cell_type == "markdown" else None
    if rows is None:
        return problems + ["the first cell has no table of what is graded (a Markdown table with a "
                           "\"points\" column: part, what you write, points, about how long)"]
    header, *body = rows
    where = {head.lower(): i for i, head in enumerate(header)}
    column, write = where["points"], next((i for h, i in where.items() if "write" in h), 1)
    covered: list[int] = []
    for row in body:
        if len(row) != len(header):
            problems.append(f"the row {' | '.join(row)!r} has {len(row)} columns, the header {len(header)}")
            continue
        stated = float(re.sub(r"[^\d.]", "", row[column]) or "nan")
        sections = _row_sections(row[0])
        if not sections:
            total = sum(points.values())
            if stated != total:
                problems.append(f"the total row says {row[column]} points; the graded cells give {total:g}")
            continue
        covered += sections
        due = sum(points.get(s, 0) for s in sections)
        if stated != due:
            problems.append(f"the row for section {row[0]!r} says {row[column]} points; its graded cells give {due:g}")
        named = set(re.findall(r"`([A-Za-z_]\w*)", row[write]))
        present = set().union(*(blanks.get(s, set()) for s in sections))
        if named != present:
            problems.append(f"the row for section {row[0]!r} names the blanks {sorted(named)}; "
                            f"its sections hold {sorted(present)}")
    for section in sorted(points):
        if covered.count(section) != 1:
            problems.append(f"section {section} has graded cells and is in {covered.count(section)} rows of the "
                            f"table of what is graded; it should be in one")
    return problems

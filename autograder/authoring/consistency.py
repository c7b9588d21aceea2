"""What ``build`` checks in a lab's notebook beyond running it: each model answer is its reference's
function, and every formula of its Markdown becomes math on the feedback page."""

from __future__ import annotations

import ast
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

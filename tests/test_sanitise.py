"""What InertHtml (autograder/pipeline/sanitise.py's allowlists) keeps of honest work: every lab's
Markdown renders to the same text after it, with every TeX macro the labs use left for MathJax,
and an unanswered written answer is left byte for byte (nbgrader's checksum tells it from an answer)."""

from __future__ import annotations

import copy
from html.parser import HTMLParser

import nbformat
import pytest

from autograder import cells
from autograder.labs import ROOT, all_labs
from autograder.pipeline.nbgrader_apps import course_config
from autograder.pipeline.restore import add_grader_notes
from autograder.pipeline.inert_html import inert_markdown, rendered
from autograder.pipeline.sanitise import ZERO_WIDTH_SPACE


class _Text(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.parts: list[str] = []

    def handle_data(self, data: str) -> None:
        self.parts.append(data)


def text_of(markup: str) -> str:
    """The text a page shows of ``markup``: no tags or comments, runs of white space as one space."""
    parser = _Text()
    parser.feed(markup)
    parser.close()
    return " ".join("".join(parser.parts).split())


@pytest.mark.parametrize("lab", all_labs(), ids=lambda lab: lab.id)
def test_every_labs_markdown_reads_the_same_after_inert_html(lab):
    for cell in cells.read(lab.source_notebook).cells:
        if cell.cell_type != "markdown":
            continue
        inert = copy.deepcopy(cell)
        inert_markdown(inert)
        after = text_of(rendered(inert.source))
        assert ZERO_WIDTH_SPACE not in after, f"a TeX macro of {lab.id} is not on TEX_WORDS: {after[:300]}"
        assert after == text_of(rendered(cell.source)), cell.source[:300]


def test_an_unanswered_written_answer_is_left_as_it_is():
    release = cells.read(all_labs()[0].release_notebook)
    [stub, *_] = [c for c in release.cells if c.cell_type == "markdown" and cells.meta(c).get("solution")]
    before = stub.source
    inert_markdown(stub)
    assert stub.source == before


def test_a_cell_nbconvert_cannot_render_is_shown_as_text_not_a_failed_submission():
    """A Markdown cell naming an attachment it does not have made nbconvert raise, and nbgrader gave
    up on the whole submission (found by the adversarial review); it is now shown as its text."""
    cell = nbformat.v4.new_markdown_cell("My plot: ![c](attachment:nope.png) and $x^2$")
    inert_markdown(cell)
    assert "nope&#46;png" in rendered(cell.source) and "<img" not in rendered(cell.source)


def test_the_graders_notes_quoting_a_students_code_are_made_inert_too():
    """FlagCheating's notes quote the student's code; InertHtml runs after it (nbgrader_config.py), so a
    TeX macro in that code is inert in the graded notebook that formgrader shows."""
    order = [p.__name__ for p in course_config(ROOT).Autograde.autograde_preprocessors]
    assert order.index("InertHtml") > order.index("FlagCheating") > order.index("GradingExecute"), order
    nb = nbformat.v4.new_notebook()
    add_grader_notes(nb, ["Flagged for review: runs the shell command !echo $\\href{javascript:alert(1)}{x}$."])
    inert_markdown(nb.cells[0])
    assert "\\href" not in rendered(nb.cells[0].source)


def test_only_the_notebook_metadata_the_pages_need_is_kept():
    """A submission's notebook metadata (widget state, a title) is dropped after grading: a plain
    nbconvert of the graded notebook loads widgets from it."""
    from nbconvert.preprocessors import ClearMetadataPreprocessor

    nb = nbformat.v4.new_notebook(metadata={"kernelspec": {"name": "python3", "display_name": "Python 3"},
                                            "language_info": {"name": "python"},
                                            "title": "<script>", "widgets": {"state": {}}})
    nb, _ = ClearMetadataPreprocessor(config=course_config(ROOT))(nb, {})
    assert set(nb.metadata) == {"kernelspec", "language_info"}

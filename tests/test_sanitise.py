"""What InertHtml (autograder/pipeline/sanitise.py's allowlists) keeps of honest work: every lab's
Markdown renders to the same text after it, with every TeX macro the labs use left for MathJax,
and an unanswered written answer is left byte for byte (nbgrader's checksum tells it from an answer)."""

from __future__ import annotations

import copy
from html.parser import HTMLParser

import pytest

from autograder import cells
from autograder.labs import all_labs
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

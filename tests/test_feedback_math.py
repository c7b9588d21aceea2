"""The feedback pages' TeX as MathML (autograder/pipeline/mathml.py, through the sanitiser's
``sanitise_math``): every lab's math converts, a written answer cannot bring active content or
HTML through "math", and TeX made to be slow or to crash the converter is shown as text, quickly.
"""

from __future__ import annotations

import time
from html.parser import HTMLParser

import nbformat
import pytest

from autograder import cells
from autograder.authoring import consistency
from autograder.labs import all_labs
from autograder.pipeline import mathml
from autograder.pipeline import inert_html
from autograder.pipeline.inert_html import MAX_MARKDOWN_CHARS, InertHtml, inert_markdown
from autograder.pipeline.sanitise import sanitise_math


class _Elements(HTMLParser):
    """Every element of a page (tag, attributes) and its text."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.elements: list[tuple[str, dict]] = []
        self.text: list[str] = []

    def handle_starttag(self, tag: str, attrs: list) -> None:
        self.elements.append((tag, dict(attrs)))

    handle_startendtag = handle_starttag

    def handle_data(self, data: str) -> None:
        self.text.append(data)


def parsed(markup: str) -> _Elements:
    parser = _Elements()
    parser.feed(markup)
    parser.close()
    return parser


page_of = consistency.feedback_page_markup


@pytest.mark.parametrize("lab", all_labs(), ids=lambda lab: lab.id)
def test_every_labs_math_becomes_mathml(lab):
    nb = cells.read(lab.source_notebook)
    assert consistency.formulas_left_as_text(nb) == []
    converted = sum(tag == "math" for cell in nb.cells if cell.cell_type == "markdown"
                    for tag, _ in parsed(page_of(cell.source)).elements)
    assert converted >= 20, converted


def test_a_formula_split_by_a_markdown_list_is_named():
    """A wrapped line inside $...$ that begins with "+" starts a list and leaves the formula as TeX
    (the new-maintainer trial of stop 46 lost 13 minutes to it; build now names the cell)."""
    nb = nbformat.v4.new_notebook(cells=[
        nbformat.v4.new_markdown_cell("The update is $x = x_p + \\alpha r$, on one line."),
        nbformat.v4.new_markdown_cell("The update is $x = x_p\n+ \\alpha r$, wrapped badly.")])
    [left] = consistency.formulas_left_as_text(nb)
    assert left.startswith("cell 1: $x = x_p")


def test_text_that_only_looks_like_math_stays_text():
    page = page_of("It costs $5 and $6, and `$x$` is code.\n\n```\n$$y$$\n```")
    assert "<math" not in page and "$5 and $6" in page and "<code>$x$</code>" in page


HOSTILE = [
    r"$<img src=x onerror=alert(1)>$",
    r"$$<script>alert(1)</script>$$",
    r"$\href{javascript:alert(1)}{click}$",
    r"$\style{position:fixed;top:0;left:0;width:100%;height:100%}{x}$",
    r"$\class{x}{y}$ $\cssId{notebook}{z}$ $\unicode{x3C}$",
    r"$\text{<img src=x onerror=alert(1)>}$",
    r"$\text{</mtext><img src=x onerror=alert(1)><mtext>}$",
    r"$\text{<a href='javascript:alert(1)'>a</a>}$",
    r"$\text{<!-- x --><svg onload=alert(1)>}$",
    r"$\mbox{<math><annotation-xml encoding='text/html'><img src=x onerror=alert(1)></annotation-xml></math>}$",
    r"$\color{white}{hidden}$ $\rule{100cm}{100cm}$ $\hspace{-999em}x$ $\hspace{999em}y$",
    r"$\newcommand{\x}{\href{javascript:alert(1)}{y}}\x$ $\def\y{z}\y$",
    r"\[\href{javascript:alert(1)}{x}\] \(\style{color:red}{x}\)",
    "<math><mi href=\"javascript:alert(1)\" onclick=\"alert(1)\">raw</mi><annotation-xml><img src=x onerror=alert(1)></annotation-xml></math>",
    "<div>$\\text{&lt;img src=x onerror=alert(1)&gt;}$</div>",
]


@pytest.mark.parametrize("markdown", HOSTILE)
def test_hostile_tex_in_a_written_answer_brings_no_active_content(markdown):
    page = page_of(markdown)
    for tag, attributes in parsed(page).elements:
        assert tag in mathml.TAGS | {"p", "div", "code", "pre", "img"}, (tag, page)  # an inert <img>: no src
        for name, value in attributes.items():
            assert not name.startswith("on") and name not in ("href", "src", "style", "class", "id",
                                                                "mathcolor", "mathbackground", "mathsize"), (tag, name, page)
            assert "javascript" not in (value or "").lower(), page
            if name in mathml.LENGTHS:
                assert mathml.attribute(name, value) == value, (name, value)


def test_a_macro_off_the_list_leaves_its_formula_as_text():
    """InertHtml puts a zero-width space after such a macro's backslash: the formula is not converted as
    the letters of a control symbol the converter does not know (it was, before TEX_SYMBOLS)."""
    page = page_of(r"$\href{javascript:alert(1)}{click}$ and $\frac{1}{2}$")
    assert page.count("<math") == 1 and "click" in page and "href" in page and "<mi>h</mi>" not in page


@pytest.mark.parametrize("tex", [
    "{" * 5000 + "x" + "}" * 5000,                                     # nesting past Python's recursion limit
    r"\frac{" * 300 + "x" + "}{y}" * 300,
    "x+" * 50_000,                                                     # far past MAX_TEX
    r"\begin{bmatrix}" + r"\\".join(["&".join(["1"] * 40)] * 40) + r"\end{bmatrix}",
    r"\newcommand{\a}{\a\a}\a",                                        # a macro that doubles itself
    r"\frac{a}{", r"x^1^2^3", r"\left(", r"\end{matrix}", r"\sqrt[", "}" * 100,
])
def test_pathological_tex_is_shown_as_text_without_crashing_or_stalling(tex):
    start = time.monotonic()
    markdown = f"Answer: ${tex}$ and then $x^2$."
    page = page_of(markdown)
    assert time.monotonic() - start < 5, "the conversion stalled"
    # a cell too long to render as Markdown is text, math and all (inert_html.MAX_MARKDOWN_CHARS)
    assert "<math" in page or len(markdown) > MAX_MARKDOWN_CHARS, "the honest formula after it is not converted"
    assert page.count("<math") <= 2


def test_a_page_of_many_formulas_stops_converting_when_its_budget_is_spent(monkeypatch):
    """A written answer of 20,000 formulas converts for PAGE_SECONDS at most, then shows TeX as text;
    so does finding formulas in text made to be slow to search (an opening without its closing)."""
    monkeypatch.setattr(mathml, "PAGE_SECONDS", 0.05)
    mathml.start_page()
    start = time.monotonic()
    page = sanitise_math("<p>" + " ".join([r"$\frac{a}{b}$"] * 1_400) + "</p>")  # just under MAX_TEXT
    assert time.monotonic() - start < 5
    assert 0 < page.count("<math") < 1_400 and r"$\frac{a}{b}$" in page
    assert mathml.formulas("$x$") == [("$x$", None)], "the budget is spent"
    mathml.start_page()
    assert mathml.formulas("$x$")[0][1] is not None, "the next page gets its own budget"


def test_text_made_slow_to_search_for_formulas_is_searched_in_bounded_time():
    """An opening ``\\[`` without its closing, 4,900 times (just under MAX_TEXT): each search reaches MAX_TEX
    characters at most."""
    mathml.start_page()
    start = time.monotonic()
    page = sanitise_math("<p>" + "\\[a " * 4_900 + " $x$</p>")
    assert time.monotonic() - start < 10 and "<math" in page


def test_markup_in_a_text_argument_leaves_its_formula_as_text():
    """An adversarial review of issue 36: latex2mathml copies the argument of \\text into <mtext> as it is, so that
    it could close it and open MathML elements of its own, nested <mpadded voffset> that lifted a formula over the
    page's score; and markup the check could not parse (<![x[) raised out of it, and the page was never written."""
    lifted = (r"$\text{</mtext><mpadded/width='0'/height='0'/depth='0'><mpadded/voffset='9.90em'>"
              r"24.0 of 24.0 points<mtext>}$ and $x < y$ and $\text{<![x[}$")
    page = page_of(lifted)
    assert all(tag != "mpadded" and "voffset" not in attributes for tag, attributes in parsed(page).elements), page
    assert page.count("<math") == 1, "only the honest $x < y$ is MathML"
    assert mathml.mathml(r"\text{<![x[}", display=False) is None
    assert mathml.mathml(r"\text{if } x < y", display=False) is None and mathml.mathml(r"x < y", display=False)


def test_a_markdown_cell_too_long_to_render_quickly_is_shown_as_text():
    """The same review: nbconvert's Markdown takes time quadratic in a text of \\( (150 KB took two minutes of a
    grading worker), and one search for formulas in 1 MB took 15 s, past the page's budget."""
    cell = nbformat.v4.new_markdown_cell("\\\\(" * 50_000)
    start = time.monotonic()
    inert_markdown(cell)
    assert time.monotonic() - start < 5 and cell.source.startswith("<div><pre>"), cell.source[:80]
    mathml.start_page()
    start = time.monotonic()
    assert mathml.formulas("\\(" + "x" * 1_000_000) == [("\\(" + "x" * 1_000_000, None)]
    assert time.monotonic() - start < 1


def test_a_tag_or_any_command_that_copies_markup_leaves_its_formula_as_text():
    """The re-attack of issue 36's review: \\tag copies its argument into <mtext> as \\text did, and nested <mover>
    stacks of tall <mspace> lifted a forged '24.0 of 24.0 points' over the summary. A formula in which a < makes
    elements is text, whichever command copied it; a < in math is one <mo>, as \\lt is."""
    lifted = (r"$x\tag{</mtext><mpadded/width='0'/height='0'/depth='0'><mover><mspace/height='9.90em'/>"
              r"<mtext>24.0 of 24.0 points</mtext></mover></mpadded><mtext>}$ and $\frac{a<b}{c}$")
    page = page_of(lifted)
    assert all(tag not in ("mpadded", "mspace", "mover") for tag, _ in parsed(page).elements), page
    assert page.count("<math") == 1, "only the honest fraction is MathML"


def test_a_notebooks_markdown_renders_within_its_time_budget(monkeypatch):
    """The same re-attack: the cap on a cell does not cap a notebook (twelve cells of 10,000 characters took 40 s of the
    grader's process); the cells after MARKDOWN_SECONDS is spent are shown as text."""
    monkeypatch.setattr(inert_html, "MARKDOWN_SECONDS", 0.2)
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_markdown_cell("[`" * 2_000) for _ in range(40)])
    start = time.monotonic()
    InertHtml().preprocess(nb, {})
    assert time.monotonic() - start < 5
    assert nb.cells[-1].source.startswith("<div><pre>"), nb.cells[-1].source[:80]

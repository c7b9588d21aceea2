"""The feedback pages a student reads: written answers nobody has graded yet say "not graded yet"
(not "0 / 2"), `python -m autograder feedback` rewrites the pages after hand grading, a test cell
that earns its marks under a failed visible check says why, and long messages wrap.

One train-kf submission is graded: the solved notebook with the handout's sign error in kupdate.
Its run_filter check fails (it calls that kupdate), while run_filter earns full marks, since the
hidden tests grade it with the reference's kupdate.
"""

from __future__ import annotations

import html
import re

import nbformat
import pytest

from autograder import cells
from autograder.pipeline import grading, nbgrader_apps
from autograder.catalogues import submissions
from autograder.__main__ import main
from autograder.labs import get_lab
from autograder.catalogues.mistakes import catalogue
from gradebook_sql import formgrader_gives

LAB = get_lab("train-kf")
[MISTAKE] = [m for m in catalogue(LAB) if (m.blank, m.slug) == ("kupdate", "innovation-sign")]
STUDENT = "s001"
FORGED = "You earned every point of this lab."


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    """The submission graded: (its grade row, the course folder)."""
    class_dir, workdir = tmp_path_factory.mktemp("class"), tmp_path_factory.mktemp("course")
    nb = submissions.with_mistake(LAB, MISTAKE)
    # an adversarial review of issue 36: a cell the student adds above a written answer stood in the page's summary
    # as its question, and cell metadata that pages obey took a written answer and its score off them
    at = next(k for k, c in enumerate(nb.cells) if cells.meta(c).get("grade_id") == "derivation_1")
    nb.cells.insert(at, nbformat.v4.new_markdown_cell(f"**Derivation 1.** {FORGED}"))
    nb.cells[at + 1].metadata.update({"transient": {"remove_source": True}, "jupyter": {"source_hidden": True}})
    submissions.write(nb, class_dir, STUDENT, LAB)
    [row] = grading.grade(class_dir, workdir, jobs=1).rows
    return row, workdir


def page(workdir) -> str:
    return nbgrader_apps.feedback_page(workdir, LAB.id, STUDENT).read_text()


def panel_heading(text: str, grade_id: str) -> str:
    """The heading of the panel of the cell ``grade_id``: its label and its score."""
    after = text.split(f'<a name="{grade_id}"></a>', 1)[1]
    return re.sub(r"\s+", " ", html.unescape(re.sub(r"<[^>]*>", " ", after.split("</div>", 1)[0]))).strip()


def written(row) -> list[str]:
    return [cell for cell in row.cells if cell not in row.autograded]


def test_the_submission_is_graded_as_the_story_says(graded):
    row, workdir = graded
    assert row.lost == ["test_kupdate"]
    autograded = nbformat.read(workdir / "autograded" / STUDENT / LAB.id / LAB.notebook_name, as_version=4)
    [check] = [c for c in autograded.cells if cells.meta(c).get("grade_id") == "check_run_filter"]
    assert any(o.output_type == "error" for o in check.outputs), "the run_filter check fails with the wrong kupdate"


def test_written_answers_not_graded_yet_say_so(graded):
    row, workdir = graded
    text = page(workdir)
    assert len(written(row)) >= 2
    for cell in written(row):
        heading = panel_heading(text, cell)
        assert "not graded yet" in heading and "Score" not in heading, heading
    toc = [" ".join(html.unescape(re.sub(r"<[^>]*>", " ", li)).split()) for li in re.findall(r"<li>.*?</li>", text, re.S)]
    written_lines = [li for li in toc if "Written answer:" in li]
    assert len(written_lines) == len(written(row)) and all("not graded yet" in li for li in written_lines), written_lines
    # each entry named (issue 36: a list of "Written response", "Comment" and "Test cell" said nothing)
    # named by the release notebook's question, not by the student's look-alike cell above it
    assert any(re.match(r"Written answer: Derivation 1\b[^.]*\. Show that", li) for li in written_lines), written_lines
    assert not any(FORGED in li for li in written_lines), written_lines
    assert any(li.startswith("Test cell test_kupdate (Score: 0.0") for li in toc), toc
    assert not any(li.startswith(("Written response", "Test cell (", "Comment")) and not li.startswith("Comment on")
                   for li in toc), toc
    points = sum(row.max_cells[c] for c in written(row))
    assert f"written answers worth {points:.1f} points are not graded yet" in text
    assert panel_heading(text, "test_kupdate").startswith("Grade cell: test_kupdate Score: 0.0 /")


def test_the_page_opens_with_a_summary_and_a_link_to_the_first_cell_that_lost_points(graded):
    """Issue 36: the page opened with nbgrader's long list of every graded cell; it now says the points,
    the blanks with full marks, the written answers waiting, and where to look first, by name."""
    row, workdir = graded
    text = page(workdir)
    top = text.split('<div class="panel-body">', 1)[0]
    summary = " ".join(html.unescape(re.sub(r"<[^>]*>", " ", top.split('<ul class="kit-summary">', 1)[1].split("</ul>", 1)[0])).split())
    blanks = [c for c in row.max_cells if c.startswith("test_")]
    assert f"Blanks: {len(blanks) - 1} of {len(blanks)} earned full marks" in summary, summary
    assert f"The {len(written(row))} written answers worth" in summary, summary
    assert "Look first at the graded cell of kupdate (0.0 of" in summary and "the first cell that lost points" in summary, summary
    assert re.search(r'<a href="#test_kupdate">the graded cell of <code>kupdate</code></a>', top), top
    assert '<a name="test_kupdate"></a>' in text, "the link leads nowhere"
    # the list of every graded cell is kept, folded under the summary
    assert re.search(r"<details>\s*<summary>Every graded cell", top) and top.count("<li><a href=") >= len(row.max_cells)


def test_the_page_runs_no_script_and_its_math_is_mathml(graded):
    """The page loaded MathJax from a CDN: offline its math was raw TeX, and a third-party script ran."""
    _, workdir = graded
    text = page(workdir)
    assert "<script" not in text.lower() and "mathjax" not in re.sub(r"<!--.*?-->", "", text, flags=re.S).lower()
    assert text.count("<math") > 50
    assert '<math display="block">' in text


def test_the_feedback_command_rewrites_the_pages_after_hand_grading(graded, capsys):
    row, workdir = graded
    first, *rest = written(row)
    hand = row.max_cells[first] - 0.5
    formgrader_gives(nbgrader_apps.course_config(workdir).CourseDirectory.db_url, LAB.id, STUDENT, {first: hand})
    assert "not graded yet" in panel_heading(page(workdir), first)  # nothing changes by itself
    assert main(["feedback", "--workdir", str(workdir)]) == 0
    assert "Rewrote the feedback of 1 graded submission in" in capsys.readouterr().out
    text = page(workdir)
    assert f"Score: {hand:.1f} / {row.max_cells[first]:.1f}" in panel_heading(text, first)
    assert all("not graded yet" in panel_heading(text, cell) for cell in rest)
    # the written answer comes before kupdate in the notebook: it is now the first cell that lost points
    assert re.search(rf'<b>Look first at</b>\s*<a href="#{first}">the written answer', text), "the summary is not rewritten"
    with open(workdir / "grades.csv") as handle:
        header, values = [line.rstrip("\n").split(",") for line in handle][:2]
    assert float(dict(zip(header, values))[first]) == hand


def test_a_full_marks_cell_under_a_failed_check_says_why(graded):
    row, workdir = graded
    text = page(workdir)
    assert row.cells["test_run_filter"] == row.max_cells["test_run_filter"] > 0
    notes = {re.search(r"The visible check of (\w+) above failed", html.unescape(n)).group(1): html.unescape(n)
             for n in re.findall(r'<div class="panel-footer kit-note">(.*?)</div>', text, re.S)}
    assert "run_filter" in notes, "no note at run_filter"
    assert "kupdate" not in notes, "kupdate lost its marks: its own check failing needs no note"
    assert "your kupdate, which loses its marks" in notes["run_filter"]
    # the note sits in run_filter's test cell, right after its heading
    cell = text.split('<a name="test_run_filter"></a>', 1)[1].split('<a name="', 1)[0]
    assert "The visible check of run_filter above failed" in html.unescape(cell)


def test_long_messages_wrap(graded):
    _, workdir = graded
    style = " ".join(re.findall(r"<style[^>]*>(.*?)</style>", page(workdir), re.S))
    rule = re.search(r"div\.output_area pre[^{]*\{([^}]*)\}", style)
    assert rule, "no rule for the output's <pre>"
    assert "white-space: pre-wrap" in rule.group(1) and "overflow-wrap: break-word" in rule.group(1)



def test_the_page_names_each_written_answer_by_the_labs_question_and_obeys_no_metadata_of_the_students(graded):
    row, workdir = graded
    text = page(workdir)
    toc = [" ".join(html.unescape(re.sub(r"<[^>]*>", " ", li)).split()) for li in re.findall(r"<li>.*?</li>", text, re.S)]
    [line] = [li for li in toc if "Derivation 1" in li and "Written answer" in li]
    assert FORGED not in line and "Show that the minimiser" in line, line
    autograded = nbformat.read(workdir / "autograded" / STUDENT / LAB.id / LAB.notebook_name, as_version=4)
    assert not [c.metadata for c in autograded.cells if {"transient", "jupyter"} & set(c.metadata)]
    # the answer (the model answer's words) and its heading with the score are on the page
    assert "convex quadratic" in html.unescape(re.sub(r"<[^>]*>", "", text))
    heading = panel_heading(text, "derivation_1")  # graded by hand by an earlier test of this module, or not yet
    assert heading.startswith("Student's answer") and ("Score:" in heading or "not graded yet" in heading), heading

"""Every source notebook follows the kit's conventions (docs/adding-a-lab.md)."""

import ast
import inspect
import re

import nbformat

from nbgrader.nbgraderformat import MetadataValidator

from autograder import cells
from autograder.cells import BEGIN_HIDDEN, BEGIN_SOLUTION, END_HIDDEN, END_SOLUTION
from autograder.authoring import consistency
from over_labs import LABS, over_labs


@over_labs
def test_metadata_is_valid_nbgrader_schema_3(lab):
    nb = cells.read(lab.source_notebook)
    MetadataValidator().validate_nb(nb)
    for cell in nb.cells:
        if "nbgrader" in cell.metadata:
            assert cell.metadata.nbgrader["schema_version"] == 3, cells.grade_id(cell)
    ids = [cells.grade_id(c) for c in nb.cells if "nbgrader" in c.metadata]
    assert len(ids) == len(set(ids)), "grade_ids must be unique"


@over_labs
def test_notebook_starts_with_credit_and_minimal_tracebacks(lab):
    nb = cells.read(lab.source_notebook)
    first = nb.cells[0].source if nb.cells[0].cell_type == "markdown" else ""
    assert "*Credit.*" in first or "*Original lab.*" in first, (
        "the first cell (Markdown) credits the handout the lab follows (*Credit.*), or says that it follows none "
        "(*Original lab.*)")
    first_code = next(c for c in nb.cells if c.cell_type == "code")
    assert cells.meta(first_code).get("locked"), "the set-up cell is locked"
    assert "%xmode Minimal" in first_code.source.splitlines()[:2], "the set-up cell starts with %xmode Minimal"
    assert nb.metadata.kernelspec.name == "python3"


@over_labs
def test_each_blank_is_one_function_identical_to_the_reference(lab):
    nb = cells.read(lab.source_notebook)
    blanks = [c for c in nb.cells if cells.is_code_answer(c)]
    assert blanks, "a lab has blanks"
    for cell in blanks:
        name = cells.grade_id(cell)
        assert cell.source.count(BEGIN_SOLUTION) == 1 and cell.source.count(END_SOLUTION) == 1, name
        [func] = cells.defined_functions(cell.source)
        assert func.name == name, f"the answer cell {name} must define {name}, not {func.name}"
        expected = ast.parse(inspect.getsource(getattr(lab.reference(), name))).body[0]
        assert [a.arg for a in func.args.args] == [a.arg for a in expected.args.args], f"{name}: signature"
    assert consistency.answers_unlike_reference(lab, nb) == []


def test_a_model_answer_unlike_its_reference_is_named(monkeypatch):
    """What build prints when a draft's answer and the reference drift apart (the new-maintainer trial
    of stop 46 found build silent about it)."""
    lab = LABS[0]
    nb = cells.read(lab.source_notebook)
    cell = next(c for c in nb.cells if cells.is_code_answer(c))
    name = cells.grade_id(cell)
    begin = next(line for line in cell.source.splitlines() if line.strip() == BEGIN_SOLUTION)
    cell.source = cell.source.replace(begin, f"{begin}\n{begin[:begin.index('#')]}unused = 0", 1)
    [sentence] = consistency.answers_unlike_reference(lab, nb)
    assert sentence.startswith(f"{name}: the model answer in the notebook differs from solutions/{lab.module}/reference.py")


@over_labs
def test_the_first_cell_says_what_is_graded(lab):
    """A student finds at the top what each part asks them to write, its points and about how long it
    takes (issue 33); the table's points and blanks are the notebook's, and "Going further" grades nothing."""
    assert consistency.summary_disagrees(cells.read(lab.source_notebook)) == []


def _summary_notebook(table: str, later: str = "") -> nbformat.NotebookNode:
    """A two-section notebook: a blank `f` (2 points) in section 1, a written answer (1 point) in
    section 2, then a "Going further" part holding ``later``'s cell, graded if ``later`` is its id."""
    v4 = nbformat.v4
    graded = {"solution": True, "grade": True, "locked": False}
    nb = v4.new_notebook(cells=[
        v4.new_markdown_cell("# Lab\n\n" + table + "\n\nText."),
        v4.new_markdown_cell("## 1. One"),
        v4.new_code_cell("def f():\n    ### BEGIN SOLUTION\n    return 1\n    ### END SOLUTION",
                         metadata={"nbgrader": {"grade_id": "f", "solution": True, "grade": False}}),
        v4.new_code_cell("validate(f)", metadata={"nbgrader": {"grade_id": "test_f", "grade": True, "points": 2}}),
        v4.new_markdown_cell("## 2. Two"),
        v4.new_markdown_cell("answer", metadata={"nbgrader": {"grade_id": "q", "points": 1, **graded}}),
        v4.new_markdown_cell("## 3. Going further"),
    ])
    if later:
        nb.cells.append(v4.new_markdown_cell("more", metadata={"nbgrader": {"grade_id": later, "points": 1, **graded}}))
    return nb


TABLE = """| part | what you write | points | about |
|---|---|---|---|
| 1. One | `f` | 2 | 30 min |
| 2. Two | a written answer | 1 | 10 min |
| **all** | 1 function, 1 written answer | **3** | **40 min** |"""


def test_a_table_of_what_is_graded_that_disagrees_is_named():
    """Each kind of disagreement is named: a row's points, its blanks, the total, a section in no row or
    in two, a graded cell after "Going further", and no table at all."""
    assert consistency.summary_disagrees(_summary_notebook(TABLE)) == []
    assert consistency.summary_disagrees(_summary_notebook(TABLE.replace("| 2 | 30", "| 3 | 30"))) == [
        "the row for section '1. One' says 3 points; its graded cells give 2"]
    assert consistency.summary_disagrees(_summary_notebook(TABLE.replace("`f`", "functions"))) == [
        "the row for section '1. One' names the blanks []; its sections hold ['f']"]
    assert consistency.summary_disagrees(_summary_notebook(TABLE.replace("**3**", "4"))) == [
        "the total row says 4 points; the graded cells give 3"]
    without_two = TABLE.replace("| 2. Two | a written answer | 1 | 10 min |\n", "")
    assert consistency.summary_disagrees(_summary_notebook(without_two)) == [
        "section 2 has graded cells and is in 0 rows of the table of what is graded; it should be in one"]
    twice = TABLE.replace("| 2. Two |", "| 1–2. Both | `f` | 3 | 40 min |\n| 2. Two |")
    assert "section 2 has graded cells and is in 2 rows of the table of what is graded; it should be in one" in (
        consistency.summary_disagrees(_summary_notebook(twice)))
    late = consistency.summary_disagrees(_summary_notebook(TABLE, later="extra"))
    assert late[0] == 'extra is graded but comes after the "Going further" heading; that part is not graded'
    assert consistency.summary_disagrees(_summary_notebook("no table here"))[0].startswith(
        "the first cell has no table of what is graded")


@over_labs
def test_each_blank_has_visible_checks_then_a_hidden_test_cell(lab):
    nb = cells.read(lab.source_notebook)
    hidden = lab.hidden_module("hidden_tests")
    by_id = {cells.grade_id(c): (i, c) for i, c in enumerate(nb.cells) if "nbgrader" in c.metadata}
    for name in cells.blank_names(nb):
        i_answer, _ = by_id[name]
        i_check, check = by_id[f"check_{name}"]
        i_test, test = by_id[f"test_{name}"]
        assert i_answer < i_check < i_test, f"{name}: answer, visible checks, hidden tests, in that order"
        assert cells.meta(check)["locked"] and not cells.meta(check)["grade"], f"check_{name} is locked, ungraded"
        assert "passed(" in check.source and "assert" not in check.source.replace("AssertionError", ""), (
            f"check_{name}: use course.checks helpers, which carry messages, and end with passed()"
        )
        assert cells.meta(test)["points"] > 0 and cells.meta(test)["locked"], f"test_{name}"
        visible, region = test.source.split(BEGIN_HIDDEN)
        assert region.split(END_HIDDEN)[0].strip().splitlines() == [
            f"from solutions.{lab.module}.hidden_tests import check_{name}",
            f"check_{name}({name})",
        ], f"test_{name}: the hidden region only calls check_{name}"
        *comments, validate = visible.strip().splitlines()
        assert all(line.startswith("#") for line in comments) and validate == f"validate({name})", (
            f"test_{name}: comments, then validate({name}) (what Validate checks), then the hidden region"
        )
        assert callable(getattr(hidden, f"check_{name}")), f"solutions.{lab.module}.hidden_tests.check_{name}"


@over_labs
def test_written_answers_hold_a_model_answer_and_a_rubric(lab):
    nb = cells.read(lab.source_notebook)
    written = [c for c in nb.cells if cells.is_answer(c) and c.cell_type == "markdown"]
    for cell in written:
        assert cells.meta(cell)["grade"] and cells.meta(cell)["points"] > 0, cells.grade_id(cell)
        lines = cell.source.strip().splitlines()
        assert lines[0].strip() == BEGIN_SOLUTION and lines[-1].strip() == END_SOLUTION, cells.grade_id(cell)
        assert "Model answer" in cell.source and "Rubric" in cell.source, cells.grade_id(cell)


@over_labs
def test_source_notebook_is_stored_executed_without_errors(lab):
    nb = cells.read(lab.source_notebook)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert all(c.execution_count is not None for c in code), "execute the source notebook before committing it"
    errors = [cells.grade_id(c) for c in code for o in c.outputs if o.output_type == "error"]
    assert not errors, f"cells with errors: {errors}"
    streams = [cells.grade_id(c) for c in code for o in c.outputs if o.output_type == "stream" and o.name == "stderr"]
    assert not streams, f"cells that write to stderr (nbgrader zeroes a test cell that does): {streams}"
    checked = [c for c in code if c.source.startswith("# NBVAL_CHECK_OUTPUT")]
    assert checked and all(c.outputs for c in checked), "at least one cell prints final numbers for nbval to check"


def _blanks_called(reference, blank: str, blanks: set[str]) -> set[str]:
    """The other blanks that the reference's ``blank`` calls, directly or through the reference
    module's own helper functions."""
    found, seen, todo = set(), {blank}, [getattr(reference, blank).__code__]
    while todo:
        code = todo.pop()
        todo += [c for c in code.co_consts if inspect.iscode(c)]
        for name in code.co_names:
            value = getattr(reference, name, None)
            if name in blanks and name != blank:
                found.add(name)
            elif name not in seen and inspect.isfunction(value) and value.__module__ == reference.__name__:
                seen.add(name)
                todo.append(value.__code__)
    return found


@over_labs
def test_a_blank_that_calls_others_is_graded_after_them(lab):
    """In grading, the grader answers a blank's calls of another blank with the reference only if
    that blank's own hidden test came earlier (autograder/pipeline/student_function.py): a test can then never collect
    the reference's answers for a later one. So the notebook grades the blanks a blank calls first."""
    order = cells.blank_names(cells.read(lab.source_notebook))
    reference = lab.reference()
    for position, blank in enumerate(order):
        later = _blanks_called(reference, blank, set(order)) - set(order[:position])
        assert not later, f"{blank} calls {sorted(later)}, whose hidden tests come after its own"


@over_labs
def test_no_comment_begins_a_line_inside_a_paragraph(lab):
    """A line that begins with ``<!--`` starts an HTML block in CommonMark, which ends the paragraph above it:
    JupyterLab and the feedback page then showed a claim marker's sentence cut in two (", and in about one
    simulated hour ..." as a paragraph of its own). A claim marker goes at the end of its sentence's line."""
    cut, spaced = [], []
    for cell in cells.read(lab.source_notebook).cells:
        if cell.cell_type != "markdown":
            continue
        lines = cell.source.split("\n")
        cut += [line for above, line in zip(lines, lines[1:]) if line.lstrip().startswith("<!--") and above.strip()]
        # and punctuation after a comment shows after a space: "within 20% of the lecture's ." (put the comment after it)
        spaced += re.findall(r"\S+ <!--(?:(?!-->).)*-->[ \t]*[,.;:)]", cell.source)
    assert cut == [], f"move these comments to the end of the line above: {cut}"
    assert spaced == [], f"put the punctuation before these comments: {spaced}"

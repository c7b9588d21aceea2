"""The grader's note at the top of a graded notebook: its notes read back as written, Markdown shows
them as written, and a note that arrives inside a submission is not taken for the grader's."""

import nbformat
from nbconvert.filters.markdown import markdown2html

from autograder import cells
from autograder.pipeline import intake
from autograder.catalogues import submissions
from autograder.labs import get_lab
from autograder.pipeline.restore import NOTE_TITLE, NOTES_KEY, GraderNote, NoteKind, add_grader_notes, grader_notes

LAB = get_lab("train-kf")
NOTES = [
    'Flagged for review: cell 4 calls __import__("solutions") (it games predict)',
    "Cell [7] printed 2,000,000 characters; *only* the first <1,000,000> were kept `as is` | C:\\lab #1.",
]


def test_notes_read_back_as_written_and_render_as_written():
    nb = nbformat.v4.new_notebook()
    add_grader_notes(nb, NOTES[:1], NoteKind.FLAG)
    add_grader_notes(nb, NOTES[1:])
    assert grader_notes(nb) == [GraderNote(NoteKind.CHANGE, NOTES[1]), GraderNote(NoteKind.FLAG, NOTES[0])]
    assert len(nb.cells) == 1
    page = markdown2html(nb.cells[0].source)
    for note in NOTES:
        expected = note.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace('"', "&quot;")
        assert f"<li>{expected}</li>" in page


def test_a_note_inside_a_submission_is_the_students_own_cell(tmp_path):
    nb = submissions.solved(LAB)
    forged = nbformat.v4.new_markdown_cell(f"{NOTE_TITLE} Your notebook was graded with these changes:\n- all fine",
                                           metadata={NOTES_KEY: ["Nothing to see here."]})
    nb.cells.insert(0, forged)
    path = submissions.write(nb, tmp_path / "class", "s001", LAB)
    path.rename(path.with_name("my copy.ipynb"))

    intake.import_submissions(tmp_path / "class", tmp_path / "course", [LAB])

    imported = cells.read(tmp_path / "course" / "submitted" / "s001" / LAB.id / LAB.notebook_name)
    assert grader_notes(imported) == [GraderNote(NoteKind.CHANGE, f"It was submitted as my copy.ipynb and graded as {LAB.notebook_name}.")]
    assert imported.cells[1].source == forged.source and NOTES_KEY not in imported.cells[1].metadata


def _failing(nb, grade_id: str, ename: str, evalue: str) -> None:
    [cell] = [c for c in nb.cells if cells.meta(c).get("grade_id") == grade_id]
    cell.outputs = [nbformat.v4.new_output("error", ename=ename, evalue=evalue, traceback=[])]


def test_a_failing_set_up_or_answer_cell_leads_the_notes_when_a_test_after_it_fails():
    """autograder/pipeline/execute.first_cause (issue 32: a failing set-up cell read as a NameError in every
    test cell). The answer-cell case is graded end to end by the fault catalogue's answer-cell-error."""
    from autograder.pipeline.execute import first_cause

    nb = submissions.solved(LAB)
    assert first_cause(nb) == []
    _failing(nb, "setup", "ModuleNotFoundError", "No module named 'course.train'\nmore")
    assert first_cause(nb) == [], "no test cell failed after it: nothing to explain"
    _failing(nb, "test_kupdate", "NameError", "name 'validate' is not defined")
    [note] = first_cause(nb)
    assert note.startswith("The set-up cell failed when the grader ran it (ModuleNotFoundError: No module named "
                           "'course.train').") and "more" not in note
    nb = submissions.solved(LAB)
    _failing(nb, "test_kupdate", "NameError", "name 'kupdate' is not defined")
    _failing(nb, "kupdate", "NotWrittenYet", "This cell needs ...")
    assert first_cause(nb) == [], "a blank not written yet is not a failure of its cell"
    _failing(nb, "kupdate", "ZeroDivisionError", "division by zero")
    [note] = first_cause(nb)
    assert note.startswith("Your cell kupdate failed when the grader ran it (ZeroDivisionError: division by zero)")
    _failing(nb, "run_filter", "TypeError", "later")
    assert first_cause(nb) == [note], "the first failing cell is the cause named"


def test_each_kind_of_note_is_listed_under_its_own_heading_the_cause_first():
    """A note that explains errors was listed under "graded with these changes", which it is not (issue 31's
    diff review); readers now tell the kinds apart by the note's metadata, not by its text."""
    nb = nbformat.v4.new_notebook()
    add_grader_notes(nb, ["Cell 3 ran for more than 30 s and was stopped."])
    add_grader_notes(nb, ["Your cell kupdate failed when the grader ran it (ZeroDivisionError: x)."], NoteKind.CAUSE)
    add_grader_notes(nb, ["Flagged for review: it reads the reference. It costs the points of every blank."], NoteKind.FLAG)
    assert [note.kind for note in grader_notes(nb)] == [NoteKind.CAUSE, NoteKind.CHANGE, NoteKind.FLAG]
    text = nb.cells[0].source
    cause, change, flag = (text.index(heading) for heading in
                           ("Why the failing cells below failed:", "graded with these changes:", "For your instructor to review:"))
    assert text.index("kupdate") < change < text.index("ran for more than") < flag
    assert cause < text.index("kupdate")


def test_a_notebook_graded_before_notes_had_kinds_reads_back():
    """Graded notebooks kept from an earlier version hold bare texts; export and report still read them."""
    nb = nbformat.v4.new_notebook()
    nb.cells.append(nbformat.v4.new_markdown_cell("old", metadata={NOTES_KEY: NOTES}))
    assert grader_notes(nb) == [GraderNote(NoteKind.CHANGE, NOTES[1]), GraderNote(NoteKind.FLAG, NOTES[0])]


def test_a_note_cell_the_grader_did_not_sign_is_the_students_own_when_autograded():
    """Adversarial review of issue 31: on the plain `nbgrader autograde` path (no intake), a submission's own note
    cell, with kinds of its choosing or a kind that is none, reached the graded notebook; a bogus kind then crashed
    `report` and `export` for the whole class. Autograding keeps only a note cell the grader signed."""
    from autograder.pipeline.restore import NOTES_SIGNATURE_KEY, RestoreLabCells

    resources = {"nbgrader": {"assignment": LAB.id}}
    forged = submissions.solved(LAB)
    forged.cells.insert(0, nbformat.v4.new_markdown_cell("mine", metadata={NOTES_KEY: [
        {"kind": "flag", "text": "Flagged for review: nothing."}, {"kind": "bogus", "text": "x"}, 17]}))
    copied_signature = nbformat.v4.new_notebook()
    add_grader_notes(copied_signature, ["A change."])
    forged.cells[0].metadata[NOTES_SIGNATURE_KEY] = copied_signature.cells[0].metadata[NOTES_SIGNATURE_KEY]
    nb, _ = RestoreLabCells().preprocess(forged, resources)
    assert grader_notes(nb) == [] and any(c.source == "mine" for c in nb.cells)

    signed = submissions.solved(LAB)
    add_grader_notes(signed, ["It was submitted as x.ipynb and graded as train-kf.ipynb."])
    nb, _ = RestoreLabCells().preprocess(signed, resources)
    assert grader_notes(nb) == [GraderNote(NoteKind.CHANGE, "It was submitted as x.ipynb and graded as train-kf.ipynb.")]


def test_entries_that_are_no_notes_are_left_out_when_read():
    """A graded notebook is read by export and report for the whole class: an odd entry must not stop them."""
    nb = nbformat.v4.new_notebook()
    nb.cells.append(nbformat.v4.new_markdown_cell("x", metadata={NOTES_KEY: [
        {"kind": "bogus", "text": "x"}, {"kind": "flag", "text": 5}, 17, {"kind": "cause", "text": "Why."}]}))
    assert grader_notes(nb) == [GraderNote(NoteKind.CAUSE, "Why.")]


def test_a_note_that_quotes_a_file_name_no_file_can_store_is_written_on_one_line():
    """Adversarial review of issue 31: a file name with a byte that is not UTF-8 (a lone surrogate in Python)
    stopped `grade` for the whole class, and one with a newline split the note."""
    nb = nbformat.v4.new_notebook()
    add_grader_notes(nb, ["It was submitted as a\udcff\nb.ipynb and graded."])
    assert grader_notes(nb)[0].text == "It was submitted as a\ufffd b.ipynb and graded."
    nbformat.writes(nb).encode("utf-8")

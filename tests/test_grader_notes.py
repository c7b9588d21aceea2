"""The grader's note at the top of a graded notebook: its notes read back as written, Markdown shows
them as written, and a note that arrives inside a submission is not taken for the grader's."""

import nbformat
from nbconvert.filters.markdown import markdown2html

from autograder import cells
from autograder.pipeline import intake
from autograder.catalogues import submissions
from autograder.labs import get_lab
from autograder.pipeline.restore import NOTE_TITLE, NOTES_KEY, add_grader_notes, grader_notes

LAB = get_lab("train-kf")
NOTES = [
    'Flagged for review: cell 4 calls __import__("solutions") (it games predict)',
    "Cell [7] printed 2,000,000 characters; *only* the first <1,000,000> were kept `as is` | C:\\lab #1.",
]


def test_notes_read_back_as_written_and_render_as_written():
    nb = nbformat.v4.new_notebook()
    add_grader_notes(nb, NOTES[:1])
    add_grader_notes(nb, NOTES[1:])
    assert grader_notes(nb) == NOTES and len(nb.cells) == 1
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
    assert grader_notes(imported) == [f"It was submitted as my copy.ipynb and graded as {LAB.notebook_name}."]
    assert imported.cells[1].source == forged.source and NOTES_KEY not in imported.cells[1].metadata

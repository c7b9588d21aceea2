"""nbgrader's Validate (the button students press before submitting) fails on a blank or
half-written notebook, naming each blank that is unwritten or fails its visible checks, and passes
on the solved one. It runs nbgrader's own Validator on the release notebooks."""

from __future__ import annotations

import nbformat
from nbgrader.validator import Validator

from autograder import cells
from autograder.catalogues import submissions
from autograder.labs import Lab, get_lab
from autograder.catalogues.mistakes import catalogue
from over_labs import over_labs


def _failed_code_cells(nb: nbformat.NotebookNode, tmp_path, name: str) -> dict[str, str]:
    """grade_id -> error of each graded code cell that Validate reports as failed."""
    path = tmp_path / name
    nbformat.write(nb, path)
    results = Validator().validate(str(path))
    assert "changed" not in results and "type_changed" not in results, results
    by_source = {c.source.strip(): cells.grade_id(c) for c in nb.cells if cells.is_autograded_test(c)}
    return {by_source[f["source"]]: f["raw_error"] for f in results.get("failed", []) if f["source"] in by_source}


def _half_written(lab: Lab) -> tuple[nbformat.NotebookNode, list[str], list[str]]:
    """The release with the first half of its code blanks written (model answers), the rest left blank."""
    nb = cells.read(lab.release_notebook)
    answers = cells.model_answers(cells.read(lab.source_notebook))
    blanks = [cells.grade_id(c) for c in nb.cells if cells.is_code_answer(c)]
    written = blanks[: len(blanks) // 2]
    for cell in nb.cells:
        if cells.is_code_answer(cell) and cells.grade_id(cell) in written:
            cell.source = answers[cells.grade_id(cell)]
    return nb, written, blanks[len(blanks) // 2:]


@over_labs
def test_validate_fails_on_the_blank_release_and_names_every_blank(lab, tmp_path):
    nb = cells.read(lab.release_notebook)
    blanks = [cells.grade_id(c) for c in nb.cells if cells.is_code_answer(c)]
    failed = _failed_code_cells(nb, tmp_path, lab.notebook_name)
    assert sorted(failed) == sorted(f"test_{name}" for name in blanks)
    for name in blanks:
        assert "NotWrittenYet" in failed[f"test_{name}"] and f"{name}()" in failed[f"test_{name}"], failed[f"test_{name}"]


@over_labs
def test_validate_passes_the_written_half_and_fails_the_rest(lab, tmp_path):
    nb, written, unwritten = _half_written(lab)
    failed = _failed_code_cells(nb, tmp_path, lab.notebook_name)
    assert sorted(failed) == sorted(f"test_{name}" for name in unwritten), failed


@over_labs
def test_validate_passes_the_solved_notebook(lab, tmp_path):
    failed = _failed_code_cells(submissions.solved(lab), tmp_path, lab.notebook_name)
    assert failed == {}


def test_validate_blames_the_blank_that_fails_its_checks_not_the_one_that_uses_it(tmp_path):
    lab = get_lab("train-kf")
    [mistake] = [m for m in catalogue(lab) if m.slug == "innovation-sign"]
    failed = _failed_code_cells(submissions.with_mistake(lab, mistake), tmp_path, lab.notebook_name)
    assert sorted(failed) == ["test_kupdate", "test_run_filter"], failed
    assert "kupdate does not pass its visible checks yet" in failed["test_kupdate"]
    assert "Check the sign of the innovation" in " ".join(failed["test_kupdate"].split())
    assert "This may come from your kupdate, which run_filter uses: it does not pass its own visible checks yet" in " ".join(
        failed["test_run_filter"].split())

"""nbgrader's Validate (the button students press before submitting) fails on a blank or
half-written notebook, naming each blank that is unwritten or fails its visible checks, and passes
on the solved one. It runs nbgrader's own Validator on the release notebooks."""

from __future__ import annotations

import re

import nbformat
from nbgrader.validator import Validator
from traitlets.config.loader import PyFileConfigLoader

from autograder import cells
from autograder.catalogues import submissions
from autograder.labs import Lab, get_lab
from autograder.catalogues.mistakes import catalogue
from autograder.release.bundle import write_jupyter_config
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
def test_validate_fails_on_the_blank_release_and_names_every_blank(lab, tmp_path, monkeypatch):
    """With the student bundle's nbgrader configuration (course/validate_order.py, loaded as the Validate
    button loads it), Validate lists every code blank first, in the notebook's order, then every written
    answer, each shown by its question (issue 34: the written answers came first where they sit first,
    and each read 'YOUR ANSWER HERE')."""
    monkeypatch.setattr(Validator, "_preprocess", Validator._preprocess)  # put back after the test
    write_jupyter_config(tmp_path / "jupyter_config")
    config = PyFileConfigLoader("nbgrader_config.py", path=str(tmp_path / "jupyter_config")).load_config()
    nb = cells.read(lab.release_notebook)
    blanks = [cells.grade_id(c) for c in nb.cells if cells.is_code_answer(c)]
    path = tmp_path / lab.notebook_name
    nbformat.write(nb, path)
    results = Validator(config=config).validate(str(path))
    tests = {c.source.strip(): cells.grade_id(c) for c in nb.cells if cells.is_autograded_test(c)}
    listed = [tests.get(f["source"], f["source"]) for f in results["failed"]]
    assert listed[: len(blanks)] == [f"test_{name}" for name in blanks], listed
    for name, failure in zip(blanks, results["failed"]):
        assert "NotWrittenYet" in failure["raw_error"] and f"{name}()" in failure["raw_error"], failure["raw_error"]
    written = [c for c in nb.cells if c.cell_type == "markdown" and cells.meta(c).get("grade")]
    assert len(listed) == len(blanks) + len(written), listed
    for answer in listed[len(blanks):]:
        assert re.match(r"(Question|Derivation|Written answer)\b", answer) and answer.endswith(
            "(Your answer to this is still empty.)"), answer
    assert len(set(listed[len(blanks):])) == len(written), "two written answers read the same"


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

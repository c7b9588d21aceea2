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


def _failed_code_cells(nb: nbformat.NotebookNode, tmp_path, name: str, config=None) -> dict[str, str]:
    """grade_id -> error of each graded code cell that Validate (with ``config``) reports as failed."""
    path = tmp_path / name
    nbformat.write(nb, path)
    results = Validator(config=config).validate(str(path))
    assert "changed" not in results and "type_changed" not in results, results
    by_source = {source: cells.grade_id(c) for c in nb.cells if cells.is_autograded_test(c)
                 for source in (c.source.strip(), _label(c))}
    return {by_source[f["source"]]: f["raw_error"] for f in results.get("failed", []) if f["source"] in by_source}


def _bundle_config(tmp_path, monkeypatch):
    """The student bundle's nbgrader configuration, loaded as the Validate button loads it; Validator is put back
    after the test."""
    monkeypatch.setattr(Validator, "_preprocess", Validator._preprocess)
    write_jupyter_config(tmp_path / "jupyter_config")
    return PyFileConfigLoader("nbgrader_config.py", path=str(tmp_path / "jupyter_config")).load_config()


def _label(cell: nbformat.NotebookNode) -> str:
    """How Validate shows a graded code cell that fails: its blank and points (course/validate_order.py)."""
    [blank] = re.findall(r"^validate\((\w+)\)", cell.source, re.MULTILINE)
    points = cells.meta(cell)["points"]
    return (f"The graded cell of {blank} ({points:g} point{'s' if points != 1 else ''}).\nValidate runs its visible "
            "checks only; its hidden tests run when you are graded.")


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
    config = _bundle_config(tmp_path, monkeypatch)
    nb = cells.read(lab.release_notebook)
    blanks = [cells.grade_id(c) for c in nb.cells if cells.is_code_answer(c)]
    path = tmp_path / lab.notebook_name
    nbformat.write(nb, path)
    results = Validator(config=config).validate(str(path))
    tests = {_label(c): cells.grade_id(c) for c in nb.cells if cells.is_autograded_test(c)}
    listed = [tests.get(f["source"], f["source"]) for f in results["failed"]]
    assert listed[: len(blanks)] == [f"test_{name}" for name in blanks], listed
    for name, failure in zip(blanks, results["failed"]):
        assert "NotWrittenYet" in failure["raw_error"] and f"{name}()" in failure["raw_error"], failure["raw_error"]
        # a student review: Validate cut the one long line of NotWrittenYet mid-word (nbgrader cuts at width - 3)
        shown = re.sub(r"\x1b\[[0-9;]*m", "", failure["raw_error"])  # Validate measures lines without colours
        too_long = [line for line in shown.splitlines() if len(line) > Validator().width - 3 - len(Validator().indent)]
        assert not too_long, too_long
    written = [c for c in nb.cells if c.cell_type == "markdown" and cells.meta(c).get("grade")]
    assert len(listed) == len(blanks) + len(written), listed
    for answer, failure in zip(listed[len(blanks):], results["failed"][len(blanks):]):
        # said once, by nbgrader (a student review: ours and nbgrader's said it twice)
        assert re.match(r"(Question|Derivation|Written answer)\b", answer) and "still empty" not in answer, answer
        assert failure["raw_error"].strip() == "You did not provide a response.", failure
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


def _written(lab: Lab, blanks: list[str], mistake: str = "") -> nbformat.NotebookNode:
    """The release with ``blanks`` written (model answers; the first with the catalogued ``mistake``)."""
    nb = cells.read(lab.release_notebook)
    answers = cells.model_answers(cells.read(lab.source_notebook))
    if mistake:
        [wrong] = [m for m in catalogue(lab) if m.slug == mistake and m.blank == blanks[0]]
        answers[blanks[0]] = wrong.apply(answers[blanks[0]])
    for cell in nb.cells:
        if cells.is_code_answer(cell) and cells.grade_id(cell) in blanks:
            cell.source = answers[cells.grade_id(cell)]
    return nb


def test_validate_names_the_unwritten_blank_that_a_written_one_calls(tmp_path, monkeypatch):
    """A student review: a written kalman_step whose kalman_gain was still a stub got the whole crash report of the
    stub, twice over (the check cell's, nested in the graded cell's), blaming kalman_gain as failing its checks."""
    lab = get_lab("castaway-bob")
    failed = _failed_code_cells(_written(lab, ["kalman_step", "joseph_covariance"]), tmp_path, lab.notebook_name,
                                _bundle_config(tmp_path, monkeypatch))
    error = " ".join(failed["test_kalman_step"].split())
    assert "kalman_step() calls kalman_gain(), which you have not written yet" in error, error
    assert "NotImplementedError in your" not in error and "got these inputs" not in error, error
    assert "the check cell" not in error, "Validate's message says once what to write, not what the check cell said"


def test_validate_gives_the_first_sentences_of_a_failing_check_once(tmp_path, monkeypatch):
    """A student review: Validate printed the check cell's whole message again under the graded cell, numbers and
    all. It now gives the verdict and the check's hint, on a few lines, and says where the rest is."""
    from course.validate_order import MORE, SHOWN_ERROR_LINES

    lab = get_lab("castaway-bob")
    # a centred window: it uses a later fix (the student review: told first to fix its start; now checked first)
    failed = _failed_code_cells(_written(lab, ["trailing_mean"], "includes-future"), tmp_path, lab.notebook_name,
                                _bundle_config(tmp_path, monkeypatch))
    error = failed["test_trailing_mean"]
    flat = " ".join(error.split())
    assert ("trailing_mean does not pass its visible checks yet. Its check cell above says: Moving the last fix to "
            "(900, 900) changed your first four estimates. An estimate must not use fixes that come after it") in flat, flat
    assert "expected" not in flat and "but got" not in flat, flat
    assert len(error.strip().splitlines()) <= SHOWN_ERROR_LINES + 1 and MORE not in error, error


def test_a_blank_that_writes_into_its_arguments_fails_its_own_check(tmp_path, monkeypatch):
    """A student review: a kalman_step that wrote into y (y -= H @ x) passed its own visible checks, and the check of
    run_rank4, which calls it, then failed and pointed at run_rank4's current term. Its own check says so now."""
    lab = get_lab("castaway-bob")
    model = cells.model_answers(cells.read(lab.source_notebook))["kalman_step"]
    nb = _written(lab, ["kalman_gain", "joseph_covariance", "transition_matrix", "observation_matrix"])
    [blank] = [c for c in nb.cells if cells.is_code_answer(c) and cells.grade_id(c) == "kalman_step"]
    blank.source = ("def kalman_step(x, P, y, A, H, Q, R, u=None):\n    x_f = A @ x if u is None else A @ x + u\n"
                    "    P_f = A @ P @ A.T + Q\n    K = kalman_gain(P_f, H, R)\n    y -= H @ x_f\n"
                    "    return x_f + K @ y, joseph_covariance(P_f, K, H, R)\n")
    failed = _failed_code_cells(nb, tmp_path, lab.notebook_name, _bundle_config(tmp_path, monkeypatch))
    flat = " ".join(failed.get("test_kalman_step", "").split())
    assert "kalman_step changed its argument y in place" in flat, (flat, model)


def test_a_step_that_draws_from_numpys_global_generator_fails_its_own_check(tmp_path, monkeypatch):
    """The rule that a random blank draws only from the rng it is given: its visible check says so, first, and
    Validate too."""
    lab = get_lab("reentry-pf")
    model = cells.model_answers(cells.read(lab.source_notebook))
    nb = _written(lab, [name for name in model if name != "pf_step"])
    [blank] = [c for c in nb.cells if cells.is_code_answer(c) and cells.grade_id(c) == "pf_step"]
    assert "rng.standard_normal(" in model["pf_step"]
    blank.source = model["pf_step"].replace("rng.standard_normal(", "np.random.standard_normal(")
    failed = _failed_code_cells(nb, tmp_path, lab.notebook_name, _bundle_config(tmp_path, monkeypatch))
    flat = " ".join(failed.get("test_pf_step", "").split())
    assert "pf_step drew random numbers from NumPy's global generator" in flat and "Draw every random number with rng" in flat, flat

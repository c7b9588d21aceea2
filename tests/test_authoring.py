"""What a lab has besides its notebook and hidden code: its row in README's table of the labs, its due
date, and, for a lab written as a draft, the notebook its draft makes (``python -m autograder build``,
autograder/authoring/build.py). tests/test_new_lab.py adds a lab with ``new`` and ``build``."""

import nbformat
import pytest
from nbgrader.nbgraderformat import ValidationError

from autograder import cells
from autograder.authoring.build import KERNELSPEC, draft_differences, notebook_from_draft
from autograder.authoring.new import readme_labs
from autograder.pipeline import late
from over_labs import LABS, about, chosen, over_labs


@about(*LABS)
def test_readme_lists_every_lab_once_and_nothing_else():
    listed = readme_labs()
    assert len(listed) == len(set(listed)), f"README's table of the labs lists a lab twice: {listed}"
    assert set(listed) == {lab.id for lab in LABS}, (
        f"README's table of the labs: rows without a lab {sorted(set(listed) - {lab.id for lab in LABS})}, "
        f"labs without a row {sorted({lab.id for lab in LABS} - set(listed))}")


@over_labs
def test_the_lab_has_a_due_date(lab):
    assert lab.id in late.read_due_dates(late.DUE_DATES), f"due_dates.toml gives {lab.id} no due date"


@about(*LABS)
def test_each_notebook_written_as_a_draft_is_what_its_draft_makes(pytestconfig):
    """The source notebook of a lab with a draft (solutions/<module>/draft.py) has the cells, sources and
    nbgrader metadata that its draft gives: nobody edited one without building from the other."""
    stale = {lab.id: found for lab in chosen(pytestconfig, LABS) if lab.draft.exists()
             if (found := draft_differences(lab.draft, cells.read(lab.source_notebook)))}
    assert not stale, f"notebooks that differ from their drafts (run `python -m autograder build <lab>`): {stale}"


DRAFT = '''# %% [markdown]
# # A lab
#
# *Original lab.*

# %% nbgrader={"grade_id": "setup", "locked": true}
# %xmode Minimal
import numpy as np

# %% nbgrader={"grade_id": "double", "solution": true}
def double(x):
    """2 x."""
    ### BEGIN SOLUTION
    return 2 * x
    ### END SOLUTION

# %% nbgrader={"grade_id": "test_double", "grade": true, "locked": true, "points": 2}
validate(double)
'''


def test_a_draft_becomes_a_notebook_with_complete_metadata_and_ids(tmp_path):
    draft = tmp_path / "draft.py"
    draft.write_text(DRAFT)
    nb = notebook_from_draft(draft)
    assert nb.metadata == {"kernelspec": KERNELSPEC}
    assert [c.id for c in nb.cells] == ["cell-0", "setup", "double", "test-double"]
    assert nb.cells[1].source.splitlines()[0] == "%xmode Minimal", "jupytext's commented magic is a magic again"
    assert [c.metadata for c in nb.cells[:2]] == [{}, {"nbgrader": {
        "grade": False, "grade_id": "setup", "locked": True, "schema_version": 3, "solution": False, "task": False}}]
    assert cells.meta(nb.cells[3]) == {"grade": True, "grade_id": "test_double", "locked": True, "points": 2,
                                       "schema_version": 3, "solution": False, "task": False}
    nbformat.validate(nb)
    draft.write_text(DRAFT.replace(', "points": 2', ""))
    with pytest.raises(ValidationError, match="points"):
        notebook_from_draft(draft)


def test_a_notebook_that_differs_from_its_draft_is_named_by_cell(tmp_path):
    draft = tmp_path / "draft.py"
    draft.write_text(DRAFT)
    nb = notebook_from_draft(draft)
    assert draft_differences(draft, nb) == []
    nb.cells[3].outputs = [nbformat.v4.new_output("stream", text="outputs do not count")]
    nb.cells[3].metadata["execution"] = {"iopub.status.idle": "2026-11-25T10:00:00Z"}
    assert draft_differences(draft, nb) == []
    nb.cells[2].source = nb.cells[2].source.replace("2 * x", "x + x")
    cells.meta(nb.cells[3])["points"] = 3
    nb.metadata.kernelspec.name = "python2"
    assert draft_differences(draft, nb) == ["the kernel is not python3", "cell double differs", "cell test-double differs"]
    del nb.cells[0]
    assert draft_differences(draft, nb) == ["the kernel is not python3",
        "the draft has the cells ['cell-0', 'setup', 'double', 'test-double'], the notebook ['setup', 'double', 'test-double']"]

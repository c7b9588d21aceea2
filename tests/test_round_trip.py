"""The grading round trip (tests/round_trip.py) of the first half of the labs; the second half is
in tests/test_round_trip_second_half.py. The pipeline's tests that need no class are here too: the
refusal to grade without the reference, and plain nbgrader from the course root."""

import os
import shutil
import subprocess
import sys

import nbformat
import pytest

from autograder.pipeline import grades
from autograder.catalogues import submissions
from autograder.pipeline.hidden_blocks import ReferenceUnavailable
from autograder.pipeline.execute import GradingExecute
from autograder.labs import ROOT
from over_labs import LABS, about
from round_trip import *  # noqa: F401,F403 (the tests, the graded fixture, the lab parametrization)
from round_trip import HALVES

HALF = HALVES[0]
pytestmark = about(*HALF)


@about()
def test_grading_refuses_to_start_without_the_reference(tmp_path, monkeypatch):
    """A hidden test that the grader's process cannot import stops the submission before any kernel
    starts (otherwise every hidden test would fail and nbgrader would still report success)."""
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(
        "### BEGIN HIDDEN TESTS\nfrom solutions.train_kf.hidden_tests import check_kupdate\ncheck_kupdate(kupdate)\n"
        "### END HIDDEN TESTS\n", metadata={"nbgrader": {"grade": True, "solution": False, "locked": True,
                                                         "points": 2, "grade_id": "test_kupdate", "schema_version": 3}})])
    monkeypatch.setitem(sys.modules, "solutions.train_kf.hidden_tests", None)  # import fails, as without the course root
    started = []
    monkeypatch.setattr(GradingExecute, "async_start_new_kernel_client", lambda self: started.append(1))
    with pytest.raises(ReferenceUnavailable, match="cannot import solutions.train_kf.hidden_tests.check_kupdate"):
        GradingExecute().preprocess(nb, {"metadata": {"path": str(tmp_path)}})
    assert started == []


@about()
def test_plain_nbgrader_autogrades_from_the_course_root(tmp_path):
    """`nbgrader generate_assignment` and `nbgrader autograde`, as an instructor types them, in a
    copy of the course root (so that the repository's own gradebook is left alone)."""
    lab = LABS[0]
    for name in ("nbgrader_config.py", "source", "solutions", "autograder", "course"):
        copy = shutil.copytree if (ROOT / name).is_dir() else shutil.copy2
        copy(ROOT / name, tmp_path / name)
    nbgrader = [sys.executable, "-m", "nbgrader"]
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    subprocess.run([*nbgrader, "generate_assignment", lab.id], cwd=tmp_path, env=env, check=True, capture_output=True)
    submitted = tmp_path / "submitted" / "student1" / lab.id / lab.notebook_name
    submitted.parent.mkdir(parents=True)
    nbformat.write(submissions.solved(lab), submitted)
    subprocess.run([*nbgrader, "autograde", lab.id], cwd=tmp_path, env=env, check=True, capture_output=True)
    [row] = grades.read_grades(tmp_path, [lab], ["student1"])
    assert row.auto_score == row.auto_max > 0

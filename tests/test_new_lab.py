"""Adding a lab as docs/adding-a-lab.md says, in a copy of the course: ``python -m autograder new`` writes
the template lab, ``build`` makes its notebook and release, and the lab passes the tests of a lab
(``pytest --lab``: structure, hidden tests, mistakes and their diagnosis, claims, release, its files);
``new`` refuses a lab that exists and an id that is not one; ``build`` names the cell that fails.

The copy is the repository without git, environments, the demo and nbgrader's working folders. Its
grading tests are not run here: a grading kernel imports the installed ``course`` (``-e .``), which is
the repository's, not the copy's, and has no course module for the new lab.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from autograder.authoring.new import labs_table, next_steps, refusals
from autograder.labs import ROOT, Lab

NOT_COPIED = {".git", ".venv", "demo", "submitted", "autograded", "feedback", "gradebook.db", "nbgrader.log",
              "grades.csv", "grades.versions.json", "exchange", "inbound", "outbound", ".pytest_cache"}
"""What the course root holds besides the course: git, environments, the demo's class, nbgrader's work."""
LAB_TESTS = ("tests/test_notebook_structure.py", "tests/test_hidden_tests.py", "tests/test_diagnosis.py",
             "tests/test_claims.py", "tests/test_release.py", "tests/test_authoring.py", "tests/test_alternatives.py",
             "tests/test_case_seeds.py", "tests/test_mutants.py")
NEW, WITH_DATA = "parcel-scales", "parcel-data"
"""The labs added: the template as it comes, and with shipped data (``new --data``)."""


def course_copy(folder: Path) -> Path:
    """A copy of the course root in ``folder``, without NOT_COPIED (at its top) and Python caches."""
    def ignored(path: str, names: list[str]) -> set[str]:
        return {n for n in names if n == "__pycache__" or (Path(path) == ROOT and (n in NOT_COPIED or n.startswith("autograde-")))}

    return Path(shutil.copytree(ROOT, folder / "course", ignore=ignored))


def run(course: Path, *args: str) -> subprocess.CompletedProcess:
    """``python <args>`` in the copy, as a maintainer types it there: without this process's PYTHONPATH."""
    env = {name: value for name, value in os.environ.items() if name != "PYTHONPATH"}
    return subprocess.run([sys.executable, *args], cwd=course, env=env, capture_output=True, text=True, timeout=1200)


@pytest.fixture(scope="module")
def course(tmp_path_factory) -> Path:
    """A copy of the course with two new labs, each written by ``new`` and built by ``build``."""
    course = course_copy(tmp_path_factory.mktemp("new-lab"))
    for options in ((NEW,), (WITH_DATA, "--data")):
        written = run(course, "-m", "autograder", "new", *options)
        assert written.returncode == 0, written.stderr
        assert written.stdout.rstrip().endswith(next_steps(Lab(options[0]), Lab(options[0]).module)), written.stdout
        built = run(course, "-m", "autograder", "build", options[0])
        assert built.returncode == 0, built.stdout + built.stderr
    return course


def test_new_writes_a_lab_that_build_turns_into_one_that_passes_the_tests_of_a_lab(course):
    module = NEW.replace("-", "_")
    assert sorted(p.name for p in (course / "solutions" / module).iterdir() if p.is_file()) == [
        "__init__.py", "alternatives.py", "claims.py", "draft.py", "hidden_tests.py", "mistakes.py", "mutants.py",
        "reference.py"]
    assert (course / "course" / f"{module}.py").exists() and (course / "release" / NEW / f"{NEW}.ipynb").exists()
    assert not (course / "source" / NEW / "draft.py").exists(), "the draft holds the answers: never in source/"
    assert (course / "course" / "data" / "parcel_data.csv").exists() and (course / "tests" / "test_parcel_data_reference.py").exists()
    due = tomllib.loads((course / "due_dates.toml").read_text())["due"]
    assert due[WITH_DATA] > due[NEW] > due["nonlinear-filters"]
    stale = run(course, "-c", "from autograder.labs import Lab; from autograder.release import data; "
                f"print(data.stale_files([Lab('{NEW}'), Lab('{WITH_DATA}')]))")
    assert stale.stdout.strip() == "[]", stale.stdout + stale.stderr  # data are optional; the shipped file is fresh
    tested = run(course, "-m", "pytest", "-q", "-p", "no:randomly", "--lab", NEW, "--lab", WITH_DATA, *LAB_TESTS,
                 "tests/test_parcel_data_reference.py", f"source/{NEW}", f"source/{WITH_DATA}", "--nbval-lax")
    assert tested.returncode == 0, tested.stdout[-5000:]
    summary = tested.stdout.strip().splitlines()[-1]
    assert " passed" in summary and "deselected" in summary and "failed" not in summary, summary


def test_build_keep_data_runs_the_notebook_on_the_shipped_data_without_rebuilding_them(course):
    """`build --keep-data` (for a change to the draft alone) leaves the shipped data file as it is; the
    plain `build` of the fixture rewrote it."""
    shipped = course / "course" / "data" / "parcel_data.csv"
    os.utime(shipped, ns=(10**18, 10**18))
    built = run(course, "-m", "autograder", "build", WITH_DATA, "--keep-data")
    assert built.returncode == 0, built.stdout + built.stderr
    assert shipped.stat().st_mtime_ns == 10**18 and "wrote course/data" not in built.stdout, built.stdout
    assert f"kept {WITH_DATA}'s shipped data as they are" in built.stdout and "no leaks found" in built.stdout, built.stdout


def test_a_lab_fresh_from_new_fails_the_test_of_template_text(course):
    """Every test of a lab passes with the template's story and README row left in (above); this one does not."""
    tested = run(course, "-m", "pytest", "-q", "-p", "no:randomly", "--lab", NEW, "tests/test_template_text.py")
    assert tested.returncode == 1, tested.stdout[-3000:]
    assert ("the template's title or story in the notebook: '# Lab parcel-scales: weighing a parcel on two scales'"
            in tested.stdout and "the template's topic in README's table of the labs" in tested.stdout), tested.stdout[-3000:]


def test_the_guide_gives_the_steps_that_new_prints_in_their_order():
    """docs/adding-a-lab.md and `new` once disagreed on the order (draft first, or course module first)."""
    assert next_steps(Lab("scalar-kf"), "scalar_kf") in (ROOT / "docs" / "adding-a-lab.md").read_text()


def test_readmes_table_of_the_labs_is_found_by_its_first_column_alone():
    lines = ["# Course", "", "| lab  | what it is about | handout |", "|:--|--|--|", "| `a-b` | x | y |", "| `c-d` | z | w |",
             "", "| lab | seconds |", "|---|---|", "| `a-b` | 3 |"]
    assert labs_table(lines) == range(4, 6)
    with pytest.raises(ValueError, match="no table of the labs"):
        labs_table(["| name | topic |", "|---|---|", "| `a-b` | x |"])


@pytest.mark.parametrize("lab, topic, says", [
    ("train-kf", "train_kf", "The lab train-kf exists already"),
    ("Scalar_KF", "scalar_kf", "'Scalar_KF' is not a lab id"),
    ("2d-kf", "kf", "'2d-kf' is not a lab id"),
    ("import", "imports", "'import' is not a lab id"),
    ("other-lab", "train", "course/train.py exists already"),
    ("other-lab", "Train", "'Train' cannot name a Python module"),
    ("scalar-kf2", "scalar_kf2", None),
])
def test_new_refuses_a_lab_that_exists_and_a_name_that_cannot_be_one(lab, topic, says):
    found = refusals(lab, topic)
    assert (says in " ".join(found)) if says else found == [], found


def test_new_refuses_a_lab_it_has_added_and_writes_nothing(course):
    before = {p: p.stat().st_mtime_ns for p in course.rglob("*") if "__pycache__" not in p.parts}
    refused = run(course, "-m", "autograder", "new", NEW)
    assert refused.returncode == 1
    assert refused.stderr.strip() == (f"new: The lab {NEW} exists already (source/{NEW}/, solutions/parcel_scales/ or "
                                      "tests/test_parcel_scales_reference.py). "
                                      f"due_dates.toml or README's table of the labs has {NEW} already. course/parcel_scales.py "
                                      "exists already: name the new lab's course module with --topic.")
    assert {p: p.stat().st_mtime_ns for p in course.rglob("*") if "__pycache__" not in p.parts} == before


def test_build_names_each_cell_that_fails_by_its_line_in_the_draft(tmp_path):
    course = course_copy(tmp_path)
    assert run(course, "-m", "autograder", "new", NEW).returncode == 0
    draft = course / "solutions" / NEW.replace("-", "_") / "draft.py"
    draft.write_text(draft.read_text().replace("check_close(x, 12.0,", "check_close(x, 13.0,"))
    line = draft.read_text().splitlines().index('# %% nbgrader={"grade_id": "check_fuse", "locked": true}') + 1
    built = run(course, "-m", "autograder", "build", NEW)
    assert built.returncode == 1
    assert ("2 problems in the cells of solutions/parcel_scales/draft.py" in built.stdout
            and f"  line {line}, cell check_fuse: AssertionError: x for fuse(10, 1, 20, 4) is not right: expected 13 "
                "but got 12." in built.stdout
            and "cell test_fuse: NotPassingYet: fuse does not pass its visible checks yet." in built.stdout), built.stdout
    assert not (course / "release" / NEW).exists(), "a notebook that fails is not released"

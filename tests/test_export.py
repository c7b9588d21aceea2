"""Grades exports: `grade` records the environment beside grades.csv, and after the written answers
are graded by hand in formgrader, `nbgrader export` (the kit's exporter) puts those scores into
grades.csv without grading again. Regrading asks for the hand grades to be confirmed again."""

import csv
import json
from importlib import metadata

import nbformat
import pytest
from nbgrader.api import Gradebook
from nbgrader.coursedir import CourseDirectory

from autograder.pipeline import grading, grades, nbgrader_apps
from autograder.catalogues import submissions
from autograder.labs import ROOT, get_lab
from gradebook_sql import formgrader_gives, nbgrader_export

LAB = get_lab("train-kf")


def read_csv(path) -> dict[str, str]:
    with open(path) as handle:
        [row] = list(csv.DictReader(handle))
    return row


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    """One solved submission of train-kf, graded: the class folder and the course folder."""
    class_dir, workdir = tmp_path_factory.mktemp("class"), tmp_path_factory.mktemp("course")
    path = class_dir / "s001" / LAB.id / LAB.notebook_name
    path.parent.mkdir(parents=True)
    nbformat.write(submissions.solved(LAB), path)
    grading.grade(class_dir, workdir)
    return class_dir, workdir


def test_grade_records_the_versions_beside_grades_csv(graded):
    _, workdir = graded
    record = json.loads((workdir / "grades.versions.json").read_text())
    assert {name: record["packages"][name] for name in ("numpy", "scipy", "nbgrader")} == {
        name: metadata.version(name) for name in ("numpy", "scipy", "nbgrader")}
    # the course package the kernels imported (issue 32): this root's, with a hash of its files
    assert record["kernel_course"]["path"] == str((ROOT / "course").resolve())
    assert len(record["kernel_course"]["sha256"]) == 64


def test_hand_grades_reach_grades_csv_through_nbgrader_export(graded):
    class_dir, workdir = graded
    config = nbgrader_apps.course_config(workdir)
    db_url = CourseDirectory(config=config).db_url
    [row] = grades.read_grades(workdir, [LAB])
    written = [cell for cell in row.cells if cell not in row.autograded]
    assert written and all(read_csv(workdir / "grades.csv")[cell] == "" for cell in written)

    hand = {cell: row.max_cells[cell] - 1 for cell in written}
    formgrader_gives(db_url, LAB.id, "s001", hand)
    (workdir / "grades.versions.json").unlink()
    nbgrader_export(workdir)
    exported = read_csv(workdir / "grades.csv")
    assert {cell: float(exported[cell]) for cell in written} == hand
    assert float(exported["total"]) == row.auto_score + sum(hand.values())
    assert (workdir / "grades.versions.json").exists()

    # grading again keeps the hand scores, but nbgrader marks them for review (formgrader shows
    # them with a flag), so grades.csv leaves them empty until a grader saves them again
    grading.grade(class_dir, workdir)
    with Gradebook(db_url) as gb:
        for cell, score in hand.items():
            grade = gb.find_grade(cell, LAB.id, LAB.id, "s001")
            assert grade.needs_manual_grade and grade.manual_score == score
    assert all(read_csv(workdir / "grades.csv")[cell] == "" for cell in written)
    formgrader_gives(db_url, LAB.id, "s001", hand)
    nbgrader_export(workdir)
    assert {cell: float(read_csv(workdir / "grades.csv")[cell]) for cell in written} == hand


def test_an_export_holds_no_row_for_a_submission_whose_grading_was_cut_short(graded, tmp_path, capsys):
    """A submission with its gradebook rows and autograded notebook but no feedback page (a shard killed
    while it wrote the feedback: issue 35, where grades.csv then held that student with total 0): the export
    fails, names it, leaves its row out of grades.csv, and its counts add up to the class."""
    import shutil

    from autograder.__main__ import main

    _, workdir = graded
    cut = tmp_path / "course"
    shutil.copytree(workdir, cut)
    nbgrader_apps.feedback_page(cut, LAB.id, "s001").unlink()
    assert main(["export", "--workdir", str(cut)]) == 1
    said = capsys.readouterr()
    assert "Exported the grades of 0 submissions" in said.out and "lacks 1 submissions" in said.err, said
    assert "s001 train-kf: no feedback/s001/train-kf/train-kf.html" in said.err
    with open(cut / "grades.csv") as handle:
        assert list(csv.DictReader(handle)) == []


def test_grade_exits_non_zero_when_it_did_not_grade_everything_and_refuses_a_partial_sandbox(tmp_path, monkeypatch, capsys):
    """A scheduler trusts the exit status (issue 35): a folder that is not a student id is given and not graded,
    so `grade` exits 1 and says so in one line; with --require-sandbox and a partial sandbox it grades nothing."""
    from autograder.__main__ import main

    class_dir = tmp_path / "class"
    for student in ("s001", "=2+5"):
        path = class_dir / student / LAB.id / LAB.notebook_name
        path.parent.mkdir(parents=True)
        nbformat.write(submissions.solved(LAB), path)
    assert main(["grade", str(class_dir), "--workdir", str(tmp_path / "course"), "--jobs", "1"]) == 1
    said = capsys.readouterr()
    assert "grade: not everything given was graded: 1 folder not named by a student id." in said.err, said.err
    assert "s001" in read_csv(tmp_path / "course" / "grades.csv")["student"]
    monkeypatch.setenv("KIT_SANDBOX", "files")
    assert main(["grade", str(class_dir), "--workdir", str(tmp_path / "strict"), "--require-sandbox"]) == 1
    assert "grading refuses to start without the whole sandbox" in capsys.readouterr().err
    assert not (tmp_path / "strict").exists()

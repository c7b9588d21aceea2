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

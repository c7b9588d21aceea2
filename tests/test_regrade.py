"""Regrading after a test fix changes only what the fix affects.

In a copy of the course (so that the repository's hidden tests stay as they are), a small class of
train-kf is graded; then the hidden test of one blank is fixed, as an instructor would edit
solutions/train_kf/hidden_tests.py, and the class is regraded in the same course folder. Only
that blank's test cell changes, and only for the students whose answers the fix judges
differently.
"""

import csv
import shutil
import subprocess
import sys

import nbformat

from autograder import cells
from autograder.catalogues import submissions
from autograder.labs import ROOT, get_lab
from autograder.catalogues.mistakes import catalogue

LAB = get_lab("train-kf")

FIX = '''

@diagnosed
def check_predict(func):
    """The fixed test: B_f is tested in kupdate and run_filter, so predict is graded on x_f only."""
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(1104)
    for n, _ in SIZES:
        x, B, A, Q = rng.standard_normal(n), random_spd(rng, n), rng.standard_normal((n, n)), random_spd(rng, n)
        with case(n=_state(n)):
            x_f, _ = check_pair(func(x.copy(), B.copy(), A.copy(), Q.copy()), "predict(x, B, A, Q)", "x_f", "B_f")
            check_close(check_array(x_f, f"x_f with n = {n}", (n,)), ref.predict(x, B, A, Q)[0],
                        f"x_f on a random case with n = {n}", show_expected=False)
'''


def grade(course, class_dir, workdir) -> dict[str, dict[str, str]]:
    """`python -m autograder grade` run from the course copy: student -> their grades.csv row."""
    subprocess.run([sys.executable, "-m", "autograder", "grade", str(class_dir), "--workdir", str(workdir)],
                   cwd=course, check=True, capture_output=True)
    with open(workdir / "grades.csv") as handle:
        return {record["student"]: record for record in csv.DictReader(handle)}


def test_regrading_after_a_test_fix_changes_only_that_cell_for_the_students_it_affects(tmp_path):
    course = tmp_path / "kit"
    shutil.copytree(ROOT, course, ignore=shutil.ignore_patterns(
        ".git", ".venv", "demo", "submitted", "autograded", "feedback", "gradebook.db", "grades.csv", "grades.versions.json", "*.log", "__pycache__"))
    mistakes = {m.slug: m for m in catalogue(LAB) if m.blank == "predict"}
    # no-Q gets B_f wrong (the fix forgives it); mean-not-moved gets x_f wrong (it does not)
    notebooks = {
        "no_q": submissions.with_mistake(LAB, mistakes["no-Q"]),
        "mean_not_moved": submissions.with_mistake(LAB, mistakes["mean-not-moved"]),
    }
    class_dir, workdir = tmp_path / "class", tmp_path / "graded"
    for student, nb in notebooks.items():
        path = class_dir / student / LAB.id / LAB.notebook_name
        path.parent.mkdir(parents=True)
        nbformat.write(nb, path)

    before = grade(course, class_dir, workdir)
    assert before["no_q"]["test_predict"] == before["mean_not_moved"]["test_predict"] == "0"
    hidden = course / "solutions" / "train_kf" / "hidden_tests.py"
    hidden.write_text(hidden.read_text() + FIX)
    after = grade(course, class_dir, workdir)

    changed = {(student, column) for student in before for column in before[student]
               if before[student][column] != after[student][column]}
    # no_q's reason for losing test_predict leaves its notes too
    assert changed - {("no_q", "notes")} == {("no_q", "test_predict"), ("no_q", "total")}
    assert "test_predict" not in after["no_q"].get("notes", "")
    [points] = [cells.meta(c)["points"] for c in cells.read(LAB.source_notebook).cells
                if cells.meta(c).get("grade_id") == "test_predict"]
    assert float(after["no_q"]["test_predict"]) == points > 0
    assert float(after["no_q"]["total"]) == float(before["no_q"]["total"]) + float(after["no_q"]["test_predict"])

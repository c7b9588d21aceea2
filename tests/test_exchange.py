"""A course on JupyterHub with nbgrader's exchange (issue 36), end to end: `nbgrader release_assignment`,
`fetch_assignment` and `submit` by two students (alice solved, late; bob with a catalogued mistake, on time),
`collect`, `python -m autograder grade submitted` on the collected layout, `release_feedback`, and
`fetch_feedback`: each student finds their own feedback with the score that grades.csv has.

Each person is a separate HOME in a temporary folder, and the exchange is a temporary folder too, both
given through nbgrader's configuration (``CourseDirectory.root``, ``Exchange.root``, ``Exchange.cache``,
``--student``): CI runs as root, so this needs no separate Linux users (nbgrader's ``collect`` only warns
that a submission's owner is not its student). Each submission time is fixed by ``Exchange.timestamp_format``
(a format without directives is the time itself), around the lab's due date in due_dates.toml.
"""

import os
import re
import subprocess
import sys
from datetime import datetime, timedelta, timezone
from pathlib import Path

import nbformat
import pytest

from autograder.catalogues import submissions
from autograder.catalogues.mistakes import catalogue
from autograder.labs import ROOT, get_lab
from autograder.pipeline import intake, late, nbgrader_apps
from gradebook_sql import read_csv
from test_intake import files_under
from test_late_penalty import points

LAB = get_lab("train-kf")
COURSE = nbgrader_apps.course_config().CourseDirectory.course_id


def nbgrader(home: Path, exchange: Path, *args: str, cwd: Path | None = None) -> str:
    """Run an nbgrader command as the person whose HOME is ``home`` (from ``home``, or the course root when
    ``cwd`` says so), with the exchange at ``exchange``; its log."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("JUPYTER")} | {"HOME": str(home)}
    done = subprocess.run([sys.executable, "-m", "nbgrader", *args, f"--Exchange.root={exchange}",
                           f"--Exchange.cache={home / 'nbgrader_cache'}", f"--course={COURSE}"],
                          cwd=cwd or home, env=env, capture_output=True, text=True)
    assert done.returncode == 0, f"nbgrader {args[0]} failed:\n{done.stdout}{done.stderr}"
    return done.stdout + done.stderr


def stamp(time: datetime) -> str:
    """A submission time as nbgrader's exchange writes it."""
    return time.astimezone(timezone.utc).strftime("%Y-%m-%d %H:%M:%S.%f UTC")


def test_a_class_through_nbgraders_exchange_gets_its_own_feedback_after_grade(tmp_path):
    due = late.read_due_dates(late.DUE_DATES)[LAB.id]
    mistake = next(m for m in catalogue(LAB) if m.slug == "no-Q")
    work = {"alice": (submissions.solved(LAB), due + timedelta(days=1.5)),
            "bob": (submissions.with_mistake(LAB, mistake), due - timedelta(hours=1))}
    exchange, course, instructor = tmp_path / "exchange", tmp_path / "course", tmp_path / "instructor"
    for folder in (exchange, course, instructor):
        folder.mkdir()
    as_instructor = [f"--CourseDirectory.root={course}"]
    nbgrader_apps.generate_release([LAB], course)
    nbgrader(instructor, exchange, "release_assignment", LAB.id, *as_instructor, cwd=ROOT)
    for student, (nb, time) in work.items():
        home = tmp_path / student
        home.mkdir()
        nbgrader(home, exchange, "fetch_assignment", LAB.id)
        nbformat.write(nb, home / LAB.id / LAB.notebook_name)
        nbgrader(home, exchange, "submit", LAB.id, f"--student={student}", f"--Exchange.timestamp_format={stamp(time)}")
    nbgrader(instructor, exchange, "collect", LAB.id, *as_instructor, cwd=ROOT)
    submitted = course / "submitted"
    collected = files_under(submitted)
    assert {f"{s}/{LAB.id}/{intake.SECRET}" for s in work} <= set(collected)

    graded = subprocess.run([sys.executable, "-m", "autograder", "grade", str(submitted), "--workdir", str(course),
                             "--jobs", "2"], cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)},
                            capture_output=True, text=True)
    assert graded.returncode == 0, graded.stdout + graded.stderr
    assert files_under(submitted) == collected, "grade rewrote what nbgrader collected"

    given = points(LAB)
    full = sum(p for cell, p in given.items() if cell.startswith("test_"))
    expected = {"alice": (0.2 * full, 0.8 * full), "bob": (0.0, full - given[f"test_{mistake.blank}"])}
    table = read_csv(course / "grades.csv")
    for student, (penalty, total) in expected.items():
        assert float(table[(student, LAB.id)]["late_penalty"]) == pytest.approx(penalty), student
        assert float(table[(student, LAB.id)]["total"]) == pytest.approx(total), student
    summary = " ".join(graded.stdout.split())
    assert (f"alice train-kf {full:g}/{full:g} full marks; late, total {0.8 * full:g} Late: a penalty of "
            f"{0.2 * full:g} points, so its total is {0.8 * full:g} (grades.csv's total).") in summary

    nbgrader(instructor, exchange, "release_feedback", LAB.id, *as_instructor, cwd=ROOT)
    maximum = sum(given.values())
    for student, (_, total) in expected.items():
        home = tmp_path / student
        nbgrader(home, exchange, "fetch_feedback", LAB.id, f"--student={student}")
        [page] = (home / LAB.id / "feedback").glob(f"*/{LAB.notebook_name.removesuffix('.ipynb')}.html")
        score = re.search(r"<h4>[^<]*: ([0-9.]+) of ([0-9.]+) points</h4>", page.read_text())  # the page's summary
        assert score and (float(score[1]), float(score[2])) == (pytest.approx(total), maximum), (student, score)
        assert page.read_bytes() == (course / "feedback" / student / LAB.id / page.name).read_bytes(), student

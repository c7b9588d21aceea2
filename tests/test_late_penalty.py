"""Late submissions: the due dates in due_dates.toml reach the gradebook before autograde, and
nbgrader's AssignLatePenalties takes the configured penalty (LatePenalty) from late submissions,
from an LMS download with submission times to grades.csv."""

import csv
from datetime import timedelta, timezone

import nbformat
import pytest
from nbgrader.api import Gradebook
from nbgrader.coursedir import CourseDirectory

from autograder import grading, late, submissions
from autograder.intake import collect
from autograder.labs import get_lab
from autograder.mistakes import catalogue

LAB = get_lab("train-kf")
DAY = 86400


def test_penalty_is_a_percentage_of_the_earned_points_per_started_day_capped():
    plugin = late.LatePenalty(percent_per_day=10.0, max_percent=50.0)
    assert plugin.late_submission_penalty("s", 30.0, 1) == pytest.approx(3.0)
    assert plugin.late_submission_penalty("s", 30.0, DAY) == pytest.approx(3.0)
    assert plugin.late_submission_penalty("s", 30.0, DAY + 1) == pytest.approx(6.0)
    assert plugin.late_submission_penalty("s", 30.0, 30 * DAY) == pytest.approx(15.0)
    assert plugin.late_submission_penalty("s", 0.0, 3 * DAY) == 0.0


def test_the_committed_due_dates_are_for_real_labs_with_offsets():
    due = late.read_due_dates(late.DUE_DATES)
    assert LAB.id in due and all(date.utcoffset() is not None for date in due.values())


@pytest.mark.parametrize("text, error", [
    ("[due]\nno-such-lab = 2026-10-09T23:59:00+01:00\n", "there is no lab 'no-such-lab'"),
    ("[due]\ntrain-kf = 2026-10-09T23:59:00\n", "must be a date and time with its UTC offset"),
])
def test_bad_due_dates_are_refused(tmp_path, text, error):
    path = tmp_path / "due_dates.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=error):
        late.read_due_dates(path)


def test_late_submissions_lose_the_configured_penalty(tmp_path):
    """An LMS download with submission times: on time, 1.5 days late (2 started days) with full
    marks, and 10 days late (capped) with a mistake, so that the penalty is of the earned points."""
    due = late.read_due_dates(late.DUE_DATES)[LAB.id].astimezone(timezone.utc)
    mistake = next(m for m in catalogue(LAB) if m.slug == "no-Q")
    files = {
        "ontime": (due - timedelta(hours=1), submissions.solved(LAB)),
        "late": (due + timedelta(days=1.5), submissions.solved(LAB)),
        "verylate": (due + timedelta(days=10), submissions.with_mistake(LAB, mistake)),
    }
    download = tmp_path / "lms"
    download.mkdir()
    for name, (time, nb) in files.items():
        nbformat.write(nb, download / f"{name}_{time:%Y-%m-%d-%H-%M-%S}_{LAB.notebook_name}")
    (tmp_path / "students.csv").write_text("lms_name,student_id\n" + "".join(f"{n},{n}\n" for n in files))
    collect(LAB, download, tmp_path / "students.csv", tmp_path / "SUBMISSIONS")

    workdir = tmp_path / "course"
    rows = {row.student: row for row in grading.grade(tmp_path / "SUBMISSIONS", workdir)}

    config = grading.course_config(workdir)
    per_day, cap = config.LatePenalty.percent_per_day, config.LatePenalty.max_percent
    with Gradebook(CourseDirectory(config=config).db_url) as gb:
        assert gb.find_assignment(LAB.id).duedate == due.replace(tzinfo=None)
        assert gb.find_submission(LAB.id, "late").total_seconds_late == 1.5 * DAY
    solved = rows["ontime"]
    assert solved.late_penalty == 0 and solved.auto_score == solved.auto_max
    assert rows["late"].late_penalty == pytest.approx(solved.auto_score * 2 * per_day / 100)
    earned = rows["verylate"].auto_score
    assert earned < solved.auto_score
    assert rows["verylate"].late_penalty == pytest.approx(earned * cap / 100)
    with open(workdir / "grades.csv") as handle:
        table = {record["student"]: record for record in csv.DictReader(handle)}
    for student, row in rows.items():
        assert float(table[student]["late_penalty"]) == pytest.approx(row.late_penalty)
        assert float(table[student]["total"]) == pytest.approx(row.auto_score - row.late_penalty)

"""Late submissions: the due dates in due_dates.toml reach the gradebook before autograde, and
nbgrader's AssignLatePenalties takes README's penalty (LatePenalty: 10% of the earned points per
started day, at most 50%) from late submissions, from an LMS download with submission times to
grades.csv, and never from written answers graded later by hand."""

from datetime import timedelta, timezone

import nbformat
import pytest
from nbgrader.api import Gradebook
from nbgrader.coursedir import CourseDirectory

from autograder import cells
from autograder.pipeline import grading, late, nbgrader_apps
from autograder.catalogues import submissions
from autograder.pipeline.collect import collect
from autograder.labs import get_lab
from autograder.catalogues.mistakes import catalogue
from gradebook_sql import csv_disagreements, formgrader_gives, nbgrader_export, read_csv, sheets

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


def points(lab) -> dict[str, float]:
    """grade_id -> points of every graded cell, from the source notebook's metadata."""
    return {cells.grade_id(c): float(cells.meta(c)["points"]) for c in cells.read(lab.source_notebook).cells
            if cells.meta(c).get("grade")}


def test_the_configured_penalty_is_readmes():
    """README: 10% of the earned points for every started day late, at most 50%."""
    config = nbgrader_apps.course_config()
    assert (config.LatePenalty.percent_per_day, config.LatePenalty.max_percent) == (10.0, 50.0)


def test_late_submissions_lose_readmes_penalty_and_hand_grades_are_not_penalised(tmp_path):
    """An LMS download with submission times: on time, 1.5 days late (2 started days: 20%) with full
    marks, and 10 days late (capped at 50%) with a mistake, so that the penalty is of the earned
    points. The expected penalties are computed here from the points in the source notebook. Then
    the written answers of the late submission are graded by hand (as formgrader does) and
    exported: the hand scores are added in full, after the penalty."""
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
    collect(LAB, download, tmp_path / "students.csv", tmp_path / "SUBMISSIONS", times_in_names=True)

    workdir = tmp_path / "course"
    rows = {row.student: row for row in grading.grade(tmp_path / "SUBMISSIONS", workdir).rows}
    db_url = CourseDirectory(config=nbgrader_apps.course_config(workdir)).db_url
    with Gradebook(db_url) as gb:
        assert gb.find_assignment(LAB.id).duedate == due.replace(tzinfo=None)
        assert gb.find_submission(LAB.id, "late").total_seconds_late == 1.5 * DAY

    graded = points(LAB)
    written = {cell: p for cell, p in graded.items() if cell not in rows["ontime"].autograded}
    full = sum(p for cell, p in graded.items() if cell not in written)
    earned = full - graded[f"test_{mistake.blank}"]
    expected = {"ontime": (0.0, full), "late": (0.20 * full, 0.80 * full), "verylate": (0.50 * earned, 0.50 * earned)}
    table = read_csv(workdir / "grades.csv")
    for student, (penalty, total) in expected.items():
        assert rows[student].late_penalty == pytest.approx(penalty), student
        assert float(table[(student, LAB.id)]["late_penalty"]) == pytest.approx(penalty), student
        assert float(table[(student, LAB.id)]["total"]) == pytest.approx(total), student

    assert written, "train-kf has written answers"
    hand = {cell: p - 1.0 for cell, p in written.items()}
    formgrader_gives(db_url, LAB.id, "late", hand)
    nbgrader_export(workdir)
    table = read_csv(workdir / "grades.csv")
    assert float(table[("late", LAB.id)]["late_penalty"]) == pytest.approx(0.20 * full)
    assert float(table[("late", LAB.id)]["total"]) == pytest.approx(0.80 * full + sum(hand.values()))
    assert csv_disagreements(table, sheets(db_url)) == []

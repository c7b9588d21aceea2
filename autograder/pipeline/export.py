"""``nbgrader export`` and ``python -m autograder export`` in the kit's format: the grades CSV that
``python -m autograder grade`` writes, for every submission in the gradebook.

After grading the written answers in formgrader, run ``nbgrader export`` from the course root
(``nbgrader_config.py`` makes this plugin its exporter): ``grades.csv`` is rewritten from the
gradebook with the manual scores, without grading anything again. ``--to FILE`` writes elsewhere;
``--CourseDirectory.root=WORKDIR`` exports a course graded with ``grade --workdir WORKDIR``.

Each submission's row needs its autograded notebook (the grader's notes and the reasons for lost
points are read from it) and the student needs its feedback page, both in the course folder. A
class graded in shards on machines without a shared folder has them on each machine until they
are copied into one (README: Large classes); so the export lists every submission in the gradebook
whose autograded notebook or feedback page is not in the course folder, and fails.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from nbgrader.api import Gradebook
from nbgrader.plugins import ExportPlugin

from autograder.labs import ROOT, Lab
from autograder.pipeline import grades
from autograder.pipeline.nbgrader_apps import feedback_page, gradebook_url


def not_gathered(workdir: Path, by_lab: dict[str, list[str]]) -> dict[tuple[str, str], str]:
    """(student, lab id) -> a line that says which files are missing, for each submission of ``by_lab``
    (lab id -> students) whose autograded notebook or feedback page is not in the course ``workdir``.
    The feedback page is written last, so a submission whose grading was cut short (a killed shard)
    is among them, whatever the gradebook already holds of it."""
    lines = {}
    for lab_id, students in by_lab.items():
        for student in students:
            files = (workdir / "autograded" / student / lab_id / Lab(lab_id).notebook_name,
                     feedback_page(workdir, lab_id, student))
            missing = [str(path.relative_to(workdir)) for path in files if not path.exists()]
            if missing:
                lines[student, lab_id] = f"{student} {lab_id}: no {' and no '.join(missing)}"
    return lines


def gradebook_rows(gradebook: Gradebook, workdir: Path, labs: Sequence[str] = (),
                   students: Sequence[str] = ()) -> tuple[list[grades.GradeRow], list[str]]:
    """The rows of every submission in ``gradebook`` of the course ``workdir`` (only of ``labs`` and
    ``students``, when given) that is graded and gathered there, and the submissions left out
    (``not_gathered``'s lines): what ``export`` and ``report`` read. No submission is in both."""
    by_lab = {a.name: sorted(s.student_id for s in a.submissions if not students or s.student_id in students)
              for a in gradebook.assignments if (ROOT / "source" / a.name).is_dir() and (not labs or a.name in labs)}
    everyone = sorted({student for students_of_lab in by_lab.values() for student in students_of_lab})
    rows = grades.read_grades(workdir, [Lab(lab_id) for lab_id in sorted(by_lab)], everyone) if everyone else []
    left_out = not_gathered(workdir, by_lab)
    return [row for row in rows if (row.student, row.lab) not in left_out], list(left_out.values())


def export_grades(gradebook: Gradebook, workdir: Path, dest: Path, labs: Sequence[str] = (),
                  students: Sequence[str] = ()) -> tuple[list[grades.GradeRow], list[str]]:
    """Write ``dest`` (grades.csv) with ``gradebook_rows``. Returns the rows, and the submissions left out."""
    rows, missing = gradebook_rows(gradebook, workdir, labs, students)
    grades.write_grades(rows, dest)
    return rows, missing


def incomplete(missing: list[str], dest: Path) -> str:
    """What an export with submissions left out says."""
    return (f"{dest} lacks {len(missing)} submissions of the gradebook, not graded yet or not gathered into this "
            "course folder (rerun their shard, or copy its autograded/ and feedback/ here):\n  " + "\n  ".join(missing))


def course_rows(workdir: Path) -> tuple[list[grades.GradeRow], list[str]]:
    """``gradebook_rows`` of every submission in the gradebook of the course ``workdir``."""
    with Gradebook(gradebook_url(workdir)) as gradebook:
        return gradebook_rows(gradebook, workdir)


def export_course(workdir: Path, out: Path | None = None) -> tuple[list[grades.GradeRow], list[str]]:
    """``python -m autograder export``: ``export_grades`` of every submission in the gradebook of the
    course ``workdir`` into ``out`` (default ``workdir/grades.csv``)."""
    with Gradebook(gradebook_url(workdir)) as gradebook:
        return export_grades(gradebook, workdir, out or workdir / "grades.csv")


class GradesExport(ExportPlugin):
    """One row per student and lab, one column per graded cell (``grades.write_csv``), and the
    environment record beside it (``versions.record``); fails if the gradebook has submissions
    that are not graded and gathered in the course folder."""

    def export(self, gradebook: Gradebook) -> None:
        workdir = Path(self.parent.coursedir.root)
        dest = Path(self.to) if self.to else workdir / "grades.csv"
        rows, missing = export_grades(gradebook, workdir, dest, list(self.assignment), [str(s) for s in self.student])
        self.log.info("Exported %d grade rows to %s", len(rows), dest)
        if missing:
            self.parent.fail(incomplete(missing, dest))

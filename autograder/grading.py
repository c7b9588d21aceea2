"""Running nbgrader: release, autograde, feedback, and reading the grades back from the gradebook.

Everything runs in-process through nbgrader's converters, with the course's nbgrader_config.py,
so that a batch of submissions costs one nbgrader start-up, not one per submission. A ``workdir``
is an nbgrader course directory (gradebook, submitted/, autograded/, feedback/); the course root
is the default, and the demo and the tests use a temporary one. The labs' sources always come
from the course root.
"""

from __future__ import annotations

import csv
import shutil
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path

import nbformat
from nbgrader.api import Gradebook, MissingEntry
from nbgrader.converters import Autograde, GenerateAssignment, GenerateFeedback
from nbgrader.coursedir import CourseDirectory
from nbgrader.utils import capture_log
from sqlalchemy.exc import SAWarning
from traitlets.config import Config
from traitlets.config.loader import PyFileConfigLoader

from autograder.execute import ExecuteWithReference
from autograder.labs import ROOT, Lab


# nbgrader 0.9.6 builds gradebook objects that SQLAlchemy 2 no longer adds to the session through
# backrefs; nbgrader adds them explicitly right after, so the warning is noise for every submission.
NBGRADER_SESSION_WARNING = r"Object of type <\w+> not in session, add operation along"
warnings.filterwarnings("ignore", message=NBGRADER_SESSION_WARNING, category=SAWarning)


class GradingError(RuntimeError):
    """nbgrader reported a failure; the message carries its log."""


def course_config(workdir: Path = ROOT) -> Config:
    """The course's nbgrader configuration, pointed at ``workdir``."""
    config = PyFileConfigLoader("nbgrader_config.py", path=str(ROOT)).load_config()
    config.CourseDirectory.root = str(workdir)
    config.CourseDirectory.source_directory = str(ROOT / "source")
    return config


def _coursedir(workdir: Path, lab: Lab) -> CourseDirectory:
    config = course_config(workdir)
    coursedir = CourseDirectory(config=config)
    coursedir.assignment_id = lab.id
    coursedir.student_id = "*"
    return coursedir


def _run(app_class: type, workdir: Path, lab: Lab) -> dict:
    """Run one nbgrader converter on every student of a lab; nbgrader's ``capture_log`` result."""
    coursedir = _coursedir(workdir, lab)
    app = app_class(coursedir=coursedir, config=coursedir.config)
    app.force = True
    return capture_log(app)


def generate_release(labs: list[Lab], workdir: Path = ROOT) -> None:
    """``nbgrader generate_assignment`` for each lab: writes ``workdir/release/`` and the gradebook."""
    for lab in labs:
        result = _run(GenerateAssignment, workdir, lab)
        if not result["success"]:
            raise GradingError(f"nbgrader generate_assignment failed for {lab.id}:\n{result.get('log', '')}{result['error']}")


def check_kernel_has_reference() -> None:
    """Refuse to grade unless a grading kernel, started as nbgrader starts it, imports ``solutions``.

    Raises ReferenceUnavailable (from autograder.execute) if it cannot.
    """
    config = course_config()  # loading it also sets the kernel's PYTHONPATH
    with tempfile.TemporaryDirectory() as cwd:
        ExecuteWithReference(config=config).preprocess(nbformat.v4.new_notebook(), {"metadata": {"path": cwd}})


def import_submissions(submissions: Path, workdir: Path) -> dict[str, list[str]]:
    """Copy ``submissions/<student>/<lab>/<lab>.ipynb`` into ``workdir/submitted/``.

    A ``timestamp.txt`` beside the notebook (nbgrader's submission time) is copied too, so that
    late penalties apply. Returns lab id -> the students who submitted it. Files that do not fit
    the layout are reported and skipped.
    """
    by_lab: dict[str, list[str]] = {}
    for path in sorted(submissions.glob("*/*/*.ipynb")):
        student, lab_id = path.parent.parent.name, path.parent.name
        if path.name != f"{lab_id}.ipynb":
            print(f"skipped {path}: a submission of {lab_id} must be named {lab_id}.ipynb")
            continue
        target = workdir / "submitted" / student / lab_id
        if target.exists():
            shutil.rmtree(target)
        target.mkdir(parents=True)
        shutil.copy2(path, target / path.name)
        if (path.parent / "timestamp.txt").exists():
            shutil.copy2(path.parent / "timestamp.txt", target / "timestamp.txt")
        by_lab.setdefault(lab_id, []).append(student)
    return by_lab


def autograde(lab: Lab, workdir: Path) -> str:
    """``nbgrader autograde`` every submission of a lab in ``workdir``, then write its feedback.

    nbgrader goes on past a submission it cannot grade and reports a failure at the end; that is
    not raised here, so that one bad file does not stop a class: the caller finds the
    submissions missing from the gradebook. Returns nbgrader's log.
    """
    results = [_run(app_class, workdir, lab) for app_class in (Autograde, GenerateFeedback)]
    return "".join(result.get("log", "") + result.get("error", "") for result in results)


def submitted_students(workdir: Path, lab: Lab) -> list[str]:
    """The students with a submission of ``lab`` in ``workdir/submitted``."""
    return sorted(p.parent.name for p in (workdir / "submitted").glob(f"*/{lab.id}"))


@dataclass(frozen=True)
class GradeRow:
    """One student's grade on one lab. ``cells`` maps grade cell id -> score (None: not graded yet)."""

    student: str
    lab: str
    cells: dict[str, float | None]
    max_cells: dict[str, float]
    autograded: frozenset[str]

    @property
    def total(self) -> float:
        return sum(score for score in self.cells.values() if score is not None)

    @property
    def auto_score(self) -> float:
        return sum(self.cells[c] or 0.0 for c in self.autograded)

    @property
    def auto_max(self) -> float:
        return sum(self.max_cells[c] for c in self.autograded)

    @property
    def lost(self) -> list[str]:
        """Autograded cells short of full marks."""
        return [c for c in self.cells if c in self.autograded and (self.cells[c] or 0.0) < self.max_cells[c]]


def read_grades(workdir: Path, labs: list[Lab], students: list[str] | None = None) -> list[GradeRow]:
    """Read every graded submission of these labs from ``workdir``'s gradebook."""
    rows = []
    with Gradebook(CourseDirectory(config=course_config(workdir)).db_url) as gb:
        for lab in labs:
            for student in students or submitted_students(workdir, lab):
                try:
                    submission = gb.find_submission_notebook(lab.id, lab.id, student)
                except MissingEntry:
                    continue
                cells, maxima, auto = {}, {}, set()
                for grade in sorted(submission.grades, key=lambda g: g.cell.id):
                    cells[grade.name] = grade.score if not grade.needs_manual_grade else None
                    maxima[grade.name] = grade.max_score
                    if grade.cell.cell_type == "code":
                        auto.add(grade.name)
                order = [c.name for c in gb.find_notebook(lab.id, lab.id).grade_cells]
                rows.append(
                    GradeRow(
                        student,
                        lab.id,
                        {c: cells[c] for c in order},
                        {c: maxima[c] for c in order},
                        frozenset(auto),
                    )
                )
    return rows


def write_csv(rows: list[GradeRow], path: Path) -> None:
    """One row per student and lab, one column per graded cell (empty: not in this lab, or not
    graded by hand yet), the total so far, and the total possible."""
    columns: list[str] = []
    for row in rows:
        columns += [c for c in row.cells if c not in columns]
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["student", "lab", *columns, "total", "max_score"])
        for row in rows:
            scores = ["" if row.cells.get(c) is None else f"{row.cells[c]:g}" for c in columns]
            writer.writerow([row.student, row.lab, *scores, f"{row.total:g}", f"{sum(row.max_cells.values()):g}"])


def print_table(rows: list[GradeRow], failures: dict[str, list[str]] | None = None) -> None:
    """Print the autograded score of each submission and the cells where it lost points."""
    width = max([len(r.student) for r in rows] + [7])
    print(f"{'student':<{width}}  {'lab':<16}{'autograded':>12}  lost points in")
    for row in rows:
        score = f"{row.auto_score:g}/{row.auto_max:g}"
        print(f"{row.student:<{width}}  {row.lab:<16}{score:>12}  {', '.join(row.lost) or '-'}")
    for lab_id, students in (failures or {}).items():
        for student in students:
            print(f"{student:<{width}}  {lab_id:<16}{'NOT GRADED':>12}  nbgrader could not grade this file; see its log")
    print("Written answers (derivations) are graded by hand in formgrader and are not counted above.")


def grade(submissions: Path, workdir: Path = ROOT, out_csv: Path | None = None) -> list[GradeRow]:
    """Autograde ``submissions/<student>/<lab>/<lab>.ipynb`` in the course ``workdir``.

    Refuses to start unless the grading kernel can import ``solutions``. Writes feedback HTML to
    ``workdir/feedback/`` and the grades to ``out_csv`` (default ``workdir/grades.csv``), prints
    the table, and returns the rows.
    """
    check_kernel_has_reference()
    workdir.mkdir(parents=True, exist_ok=True)
    by_lab = import_submissions(submissions, workdir)
    labs = [Lab(lab_id) for lab_id in sorted(by_lab) if (ROOT / "source" / lab_id).is_dir()]
    for lab_id in sorted(set(by_lab) - {lab.id for lab in labs}):
        print(f"skipped {lab_id}: there is no such lab (its submissions: {', '.join(by_lab[lab_id])})")
    generate_release(labs, workdir)
    logs = {lab.id: autograde(lab, workdir) for lab in labs}
    rows = read_grades(workdir, labs, None)
    graded = {(row.student, row.lab) for row in rows}
    failures = {lab.id: [s for s in by_lab[lab.id] if (s, lab.id) not in graded] for lab in labs}
    for lab_id, students in failures.items():
        if students:
            log_path = workdir / f"autograde-{lab_id}.log"
            log_path.write_text(logs[lab_id])
            print(f"{len(students)} submission(s) of {lab_id} could not be graded; nbgrader's log is in {log_path}")
    write_csv(rows, out_csv or workdir / "grades.csv")
    print_table(rows, failures)
    print(f"Grades: {out_csv or workdir / 'grades.csv'}. Feedback: {workdir / 'feedback'}.")
    return rows

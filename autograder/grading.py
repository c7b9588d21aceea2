"""Running nbgrader: release, autograde, feedback, and reading the grades back from the gradebook.

Everything runs in-process through nbgrader's converters, with the course's nbgrader_config.py,
so that a batch of submissions costs one nbgrader start-up, not one per submission. A ``workdir``
is an nbgrader course directory (gradebook, submitted/, autograded/, feedback/); the course root
is the default, and the demo and the tests use a temporary one. The labs' sources always come
from the course root.
"""

from __future__ import annotations

import csv
import multiprocessing
import re
import shutil
import sys
import textwrap
import warnings
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

import nbformat
from nbformat import NotebookNode
from nbgrader.api import Gradebook, MissingEntry
from nbgrader.converters import Autograde, GenerateAssignment, GenerateFeedback
from nbgrader.coursedir import CourseDirectory
from nbgrader.utils import capture_log
from sqlalchemy.exc import SAWarning
from traitlets.config import Config
from tqdm import tqdm
from traitlets.config.loader import PyFileConfigLoader

from autograder import cells, compare, default_jobs, late, sandbox, versions
from autograder.flag_cheating import FLAG
from autograder.labs import ROOT, Lab
from autograder.restore_cells import add_grader_notes, forget_grader_notes, grader_notes
from course.checks import count


# nbgrader 0.9.6 builds gradebook objects that SQLAlchemy 2 no longer adds to the session through
# backrefs; nbgrader adds them explicitly right after, so the warning is noise for every submission.
NBGRADER_SESSION_WARNING = r"Object of type <\w+> not in session, add operation along"
MAX_SUBMISSION_BYTES = 50_000_000
"""The largest notebook file the grader reads (a lab's solved notebook, figures and all, is under 2 MB):
a larger one is graded as empty, since reading it could take the grader's memory."""
warnings.filterwarnings("ignore", message=NBGRADER_SESSION_WARNING, category=SAWarning)


class GradingError(RuntimeError):
    """nbgrader reported a failure; the message carries its log."""


def course_config(workdir: Path = ROOT) -> Config:
    """The course's nbgrader configuration, pointed at ``workdir``."""
    config = PyFileConfigLoader("nbgrader_config.py", path=str(ROOT)).load_config()
    config.CourseDirectory.root = str(workdir)
    config.CourseDirectory.source_directory = str(ROOT / "source")
    if "db_url" not in config.CourseDirectory:
        # Grading processes (grade --jobs) share one SQLite gradebook: each waits for the lock.
        config.CourseDirectory.db_url = f"sqlite:///{workdir / 'gradebook.db'}?timeout=120"
    return config


def _coursedir(workdir: Path, lab: Lab, student: str) -> CourseDirectory:
    config = course_config(workdir)
    coursedir = CourseDirectory(config=config)
    coursedir.assignment_id = lab.id
    coursedir.student_id = student
    return coursedir


def _run(app_class: type, workdir: Path, lab: Lab, student: str = "*") -> dict:
    """Run one nbgrader converter on a lab (every student, or one); nbgrader's ``capture_log`` result."""
    coursedir = _coursedir(workdir, lab, student)
    app = app_class(coursedir=coursedir, config=coursedir.config)
    app.force = True
    return capture_log(app)


def run_checked(app_class: type, workdir: Path, lab: Lab) -> None:
    """Run one nbgrader converter on every student of a lab; raise GradingError, with its log, if it fails."""
    result = _run(app_class, workdir, lab)
    if not result["success"]:
        raise GradingError(f"nbgrader {app_class.__name__} failed for {lab.id}:\n{result.get('log', '')}{result['error']}")


def generate_release(labs: list[Lab], workdir: Path = ROOT) -> None:
    """``nbgrader generate_assignment`` for each lab: writes ``workdir/release/`` and the gradebook."""
    for lab in labs:
        run_checked(GenerateAssignment, workdir, lab)


def feedback_page(workdir: Path, lab_id: str, student: str) -> Path:
    """Where nbgrader writes a student's feedback page on a lab in the course ``workdir``."""
    return workdir / "feedback" / student / lab_id / f"{lab_id}.html"


def check_reference_available(labs: list[Lab]) -> None:
    """Refuse to grade unless this process, where the hidden tests compare, imports every hidden test
    of these labs and the reference they use.

    Raises ReferenceUnavailable (from autograder.compare) if it cannot.
    """
    course_config()  # loading it puts the course root on this process's path, as for plain nbgrader
    for lab in labs:
        for test in compare.hidden_tests(cells.read(lab.source_notebook)).values():
            test.load()


def sandbox_line() -> str:
    """What confines the grading kernels on this machine, as the grader's output says it (loudly if
    they are not fully sandboxed)."""
    status = sandbox.status()
    if status.complete:
        return f"Grading kernels are sandboxed: {status.summary}."
    return (f"WARNING: {status.summary}. The hidden tests still compare outside the kernel, so no answer can be "
            "forged, but see README (The grading kernel's sandbox) for what a kernel can reach here.")


def read_submission(folder: Path, lab: Lab) -> tuple[NotebookNode, list[str]]:
    """The notebook in a student's ``folder`` for ``lab``, and notes on anything wrong with it.

    A notebook under another name is taken if it is the only one. A file that is not a readable
    notebook (not JSON, truncated, invalid) is replaced by the blank release notebook, so that it
    is graded as an empty submission, with the reason in its notes. So is a notebook reached through
    a symbolic link (the notebook, its folder or the student's folder): the grader would read
    whatever file it points to, another student's notebook or the course's solved source. So is a
    file larger than MAX_SUBMISSION_BYTES. A grader's note that arrives inside the file becomes an
    ordinary cell of the student's: only the grader writes notes.
    """
    linked = [p for p in (folder.parent, folder, *folder.glob("*.ipynb")) if p.is_symlink()]
    if linked:
        return cells.read(lab.release_notebook), [
            f"{linked[0].name} is a symbolic link to {linked[0].readlink()}, not the student's own file; "
            "it was graded as an empty submission."
        ]
    expected = folder / lab.notebook_name
    found = sorted(folder.glob("*.ipynb"))
    if expected.exists():
        path, notes = expected, []
    elif len(found) == 1:
        path, notes = found[0], [f"It was submitted as {found[0].name} and graded as {lab.notebook_name}."]
    else:
        listed = ", ".join(p.name for p in found) or "none"
        return cells.read(lab.release_notebook), [
            f"No notebook named {lab.notebook_name} was found (notebooks there: {listed}); "
            "it was graded as an empty submission."
        ]
    size = path.stat().st_size
    if size > MAX_SUBMISSION_BYTES:
        return cells.read(lab.release_notebook), notes + [
            f"{path.name} is {size:,} bytes, more than the {MAX_SUBMISSION_BYTES:,} the grader reads; "
            "it was graded as an empty submission."
        ]
    try:
        nb = nbformat.read(path, as_version=4)
        nbformat.validate(nb)
    except Exception as error:  # not JSON, truncated, not a notebook: any of nbformat's errors
        reason = " ".join(str(error).split())[:160] or type(error).__name__
        return cells.read(lab.release_notebook), notes + [
            f"{path.name} could not be read as a notebook ({type(error).__name__}: {reason}); "
            "it was graded as an empty submission."
        ]
    forget_grader_notes(nb)
    return nb, notes


def import_submissions(submissions: Path, workdir: Path, labs: list[Lab]) -> dict[str, list[str]]:
    """Put ``submissions/<student>/<lab>/<lab>.ipynb`` into ``workdir/submitted/``, for these labs.

    Each file goes through ``read_submission``; its notes become a grader's note at the top of the
    notebook, which the feedback shows. A ``timestamp.txt`` beside the notebook (nbgrader's
    submission time) is copied too, so that late penalties apply. Returns lab id -> students.
    """
    by_lab: dict[str, list[str]] = {lab.id: [] for lab in labs}
    for lab in labs:
        for folder in sorted(p for p in submissions.glob(f"*/{lab.id}") if p.is_dir()):
            student = folder.parent.name
            nb, notes = read_submission(folder, lab)
            add_grader_notes(nb, notes)
            target = workdir / "submitted" / student / lab.id
            if target.exists():
                shutil.rmtree(target)
            target.mkdir(parents=True)
            nbformat.write(nb, target / lab.notebook_name)
            if (folder / "timestamp.txt").exists() and not (folder / "timestamp.txt").is_symlink():
                shutil.copy2(folder / "timestamp.txt", target / "timestamp.txt")
            by_lab[lab.id].append(student)
    return by_lab


def _grade_student(workdir: Path, lab_id: str, student: str) -> str:
    """Autograde, then write the feedback of, one student's submission of a lab; nbgrader's log."""
    log = []
    for app_class in (Autograde, GenerateFeedback):
        result = _run(app_class, workdir, Lab(lab_id), student)
        log.append(result.get("log", "") + result.get("error", ""))
    return "".join(log)


def autograde(by_lab: dict[str, list[str]], workdir: Path, jobs: int | None = None) -> dict[str, str]:
    """``nbgrader autograde`` and feedback for the submissions in ``workdir``: lab id -> students.

    With ``jobs > 1`` (default: one per core) the submissions are graded that many at a time in
    separate processes, which all write to the one gradebook (SQLite waits for its lock; a database
    server handles it natively). A progress bar (tqdm, on stderr) counts the graded submissions.
    nbgrader goes on past a submission it cannot grade; that is not raised here, so that one bad
    file does not stop a class: the caller finds the submissions missing from the gradebook.
    Returns nbgrader's log of each lab.
    """
    jobs = jobs or default_jobs()
    tasks = [(lab_id, student) for lab_id, students in by_lab.items() for student in students]
    logs: dict[tuple[str, str], str] = {}
    with tqdm(total=len(tasks), desc="Grading", unit="submission", file=sys.stderr, dynamic_ncols=True) as bar:
        if jobs <= 1 or len(tasks) <= 1:
            for lab_id, student in tasks:
                logs[lab_id, student] = _grade_student(workdir, lab_id, student)
                bar.update()
        else:
            with ProcessPoolExecutor(min(jobs, len(tasks)), mp_context=multiprocessing.get_context("spawn")) as pool:
                futures = {pool.submit(_grade_student, workdir, lab_id, student): (lab_id, student)
                           for lab_id, student in tasks}
                for future in as_completed(futures):
                    logs[futures[future]] = future.result()
                    bar.update()
    return {lab_id: "".join(logs[lab_id, student] for student in students) for lab_id, students in by_lab.items()}


def all_graded_labs(workdir: Path) -> list[Lab]:
    """The labs with submissions in ``workdir/submitted``."""
    names = sorted({p.name for p in (workdir / "submitted").glob("*/*") if p.is_dir()})
    return [Lab(name) for name in names if (ROOT / "source" / name).is_dir()]


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
    late_penalty: float = 0.0
    """Points taken for a late submission (nbgrader's AssignLatePenalties, autograder/late.py)."""
    notes: tuple[str, ...] = ()
    """What the grader changed before grading (the grader's note in the feedback)."""
    reasons: dict[str, str] = field(default_factory=dict)
    """Why each autograded cell short of full marks lost them: its error, or its stderr output."""

    @property
    def total(self) -> float:
        return max(0.0, sum(score for score in self.cells.values() if score is not None) - self.late_penalty)

    @property
    def auto_score(self) -> float:
        return sum(self.cells[c] or 0.0 for c in self.autograded)

    @property
    def auto_max(self) -> float:
        return sum(self.max_cells[c] for c in self.autograded)

    @property
    def flags(self) -> list[str]:
        """Why the submission is flagged for review (integrity findings); empty if it is not."""
        return [note.removeprefix(FLAG).strip() for note in self.notes if note.startswith(FLAG)]

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
                autograded = workdir / "autograded" / student / lab.id / lab.notebook_name
                try:
                    submission = gb.find_submission_notebook(lab.id, lab.id, student)
                except MissingEntry:
                    continue
                if not autograded.exists():  # nbgrader failed part-way: reported as not graded
                    continue
                cells, maxima, auto = {}, {}, set()
                for grade in sorted(submission.grades, key=lambda g: g.cell.id):
                    cells[grade.name] = grade.score if not grade.needs_manual_grade else None
                    maxima[grade.name] = grade.max_score
                    if grade.cell.cell_type == "code":
                        auto.add(grade.name)
                order = [c.name for c in gb.find_notebook(lab.id, lab.id).grade_cells]
                notes, reasons = _notes_and_reasons(autograded)
                rows.append(
                    GradeRow(
                        student,
                        lab.id,
                        {c: cells[c] for c in order},
                        {c: maxima[c] for c in order},
                        frozenset(auto),
                        submission.late_submission_penalty or 0.0,
                        notes,
                        {c: reasons[c] for c in order if c in reasons and (cells[c] or 0.0) < maxima[c]},
                    )
                )
    return rows


ANSI = re.compile(r"\x1b\[[0-9;]*m")


def _notes_and_reasons(autograded: Path) -> tuple[tuple[str, ...], dict[str, str]]:
    """The grader's notes of an autograded notebook, and for each graded cell its first error or
    its stderr output (the reasons nbgrader gives a cell 0)."""
    nb = nbformat.read(autograded, as_version=4)
    reasons = {}
    for cell in nb.cells:
        if cell.cell_type != "code" or not cells.meta(cell).get("grade"):
            continue
        errors = [o for o in cell.outputs if o.output_type == "error"]
        stderr = [o for o in cell.outputs if o.output_type == "stream" and o.name == "stderr"]
        if errors:
            reasons[cells.grade_id(cell)] = ANSI.sub("", f"{errors[0].ename}: {errors[0].evalue}")
        elif stderr:
            first = ANSI.sub("", stderr[0].text).strip().splitlines()[0]
            reasons[cells.grade_id(cell)] = f"the cell wrote to stderr, which nbgrader scores 0 ({first})"
    return tuple(grader_notes(nb)), reasons


def write_grades(rows: list[GradeRow], path: Path) -> None:
    """grades.csv (``write_csv``) and the record of the grading environment beside it (``versions.record``)."""
    write_csv(rows, path)
    versions.record(path)


def write_csv(rows: list[GradeRow], path: Path) -> None:
    """One row per student and lab, one column per graded cell (empty: not in this lab, or not
    graded by hand yet), the late penalty, the total so far (less the penalty), and the total possible."""
    columns: list[str] = []
    for row in rows:
        columns += [c for c in row.cells if c not in columns]
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["student", "lab", *columns, "late_penalty", "total", "max_score", "flagged", "notes"])
        for row in rows:
            scores = ["" if row.cells.get(c) is None else f"{row.cells[c]:g}" for c in columns]
            notes = [n for n in row.notes if not n.startswith(FLAG)] + [f"{c}: {why}" for c, why in row.reasons.items()]
            writer.writerow([row.student, row.lab, *scores, f"{row.late_penalty:g}", f"{row.total:g}",
                             f"{sum(row.max_cells.values()):g}", " | ".join(row.flags), " | ".join(notes)])


TABLE_WIDTH = 100
"""The widest the summary table gets, in characters (narrower if the terminal is)."""


def _lost_lines(row: GradeRow) -> list[str]:
    """Each lost cell once, with why it lost its points; cells that lost them for the same reason share a line."""
    by_reason: dict[str, list[str]] = {}
    for cell in row.lost:
        by_reason.setdefault(row.reasons.get(cell, "no reason was recorded"), []).append(cell)
    return [f"{', '.join(lost)}: {reason}" for reason, lost in by_reason.items()]


def format_table(rows: list[GradeRow], failures: dict[str, list[str]] | None = None, width: int | None = None) -> str:
    """The summary table: one line per submission (student, lab, autograded score, what happened),
    then the grader's notes and each lost cell with its reason, wrapped to ``width`` columns
    (default: the terminal's, at most TABLE_WIDTH); a line cut short ends in an ellipsis."""
    width = width or min(shutil.get_terminal_size((TABLE_WIDTH, 24)).columns, TABLE_WIDTH)
    names = [r.student for r in rows] + [s for students in (failures or {}).values() for s in students]
    student_w = min(max([len(n) for n in names] + [7]), 40)
    lab_w = max([len(r.lab) for r in rows] + [len(lab) for lab in failures or {}] + [3])
    lines = [f"{'student':<{student_w}}  {'lab':<{lab_w}}  {'score':>9}  result", "-" * width]
    indent = " " * 4

    def line(student: str, lab: str, score: str, result: str) -> list[str]:
        if len(student) > student_w:  # a long name on a line of its own
            return [student, f"{'':<{student_w}}  {lab:<{lab_w}}  {score:>9}  {result}"]
        return [f"{student:<{student_w}}  {lab:<{lab_w}}  {score:>9}  {result}"]

    for row in rows:
        if row.flags:
            result = "flagged for review"
        elif not row.lost:
            result = "full marks"
        else:
            result = f"lost {len(row.lost)} of {len(row.autograded)} cells"
        lines += line(row.student, row.lab, f"{row.auto_score:g}/{row.auto_max:g}", result)
        for text in [*row.notes, *_lost_lines(row)]:
            lines += textwrap.wrap(" ".join(text.split()), width, initial_indent=indent, subsequent_indent=indent + "  ",
                                   max_lines=3, placeholder=" ...", break_on_hyphens=False)
    for lab_id, students in (failures or {}).items():
        for student in students:
            lines += line(student, lab_id, "-", "not graded: see the log")
    lines.append("-" * width)
    lines += textwrap.wrap("Scores count the autograded cells only: written answers are graded by hand in formgrader.", width)
    return "\n".join(lines)


def print_table(rows: list[GradeRow], failures: dict[str, list[str]] | None = None) -> None:
    """Print ``format_table``."""
    print(format_table(rows, failures))


def grade(submissions: Path, workdir: Path = ROOT, out_csv: Path | None = None, jobs: int | None = None) -> list[GradeRow]:
    """Autograde ``submissions/<student>/<lab>/<lab>.ipynb`` in the course ``workdir``.

    Refuses to start unless this process can import the hidden tests and the reference. Grades only the
    submissions given (with ``jobs`` processes), so that regrading one student leaves everyone
    else's grades as they were. Writes feedback HTML to ``workdir/feedback/`` and the grades of
    every graded submission in the course to ``out_csv`` (default ``workdir/grades.csv``), prints
    the table, and returns the rows.
    """
    workdir.mkdir(parents=True, exist_ok=True)
    known = {p.parent.name for p in (ROOT / "source").glob("*/*.ipynb")}
    for folder in sorted(p for p in submissions.glob("*/*") if p.is_dir() and p.name not in known):
        print(f"Skipped {folder}: there is no lab called {folder.name}.")
    labs = [Lab(lab_id) for lab_id in sorted(known & {p.name for p in submissions.glob("*/*") if p.is_dir()})]
    check_reference_available(labs)
    print(sandbox_line())
    print(f"Setting up the course folder {workdir} for {count(len(labs), 'lab')} (nbgrader generate_assignment).")
    generate_release(labs, workdir)
    late.set_due_dates(labs, course_config(workdir))
    by_lab = import_submissions(submissions, workdir, labs)
    logs = autograde(by_lab, workdir, jobs)
    rows = read_grades(workdir, all_graded_labs(workdir))
    graded = {(row.student, row.lab) for row in rows}
    failures = {lab.id: [s for s in by_lab[lab.id] if (s, lab.id) not in graded] for lab in labs}
    for lab in labs:
        pages = [s for s in by_lab[lab.id] if (s, lab.id) in graded and not feedback_page(workdir, lab.id, s).exists()]
        if failures[lab.id] or pages:
            log_path = workdir / f"autograde-{lab.id}.log"
            log_path.write_text(logs[lab.id])
        if failures[lab.id]:
            print(f"{count(len(failures[lab.id]), 'submission')} of {lab.id} could not be graded; "
                  f"nbgrader's log is in {log_path}.")
        if pages:
            print(f"No feedback page was written for {count(len(pages), 'graded submission')} of {lab.id}; "
                  f"nbgrader's log is in {log_path}.")
    write_grades(rows, out_csv or workdir / "grades.csv")
    print_table(rows, failures)
    print(f"Grades: {out_csv or workdir / 'grades.csv'}. Feedback: {workdir / 'feedback'}.")
    return rows

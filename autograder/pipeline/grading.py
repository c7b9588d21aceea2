"""Grading a class: ``python -m autograder grade``. Refuses to start unless this process can import
the hidden tests, sets up the course folder and the gradebook, takes the submissions in (a shard's
only, with ``--shard``), autogrades them with nbgrader one per process at a time, writes feedback,
grades.csv, the summary table and the class report (autograder/pipeline/class_report.py).
"""

from __future__ import annotations

import multiprocessing
import sys
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

from nbgrader.converters import Autograde, GenerateFeedback
from tqdm import tqdm

from autograder import cells, default_jobs, private_paths
from autograder.kernel import sandbox
from autograder.labs import ROOT, Lab
from autograder.pipeline import class_report, late, shards
from autograder.pipeline import hidden_blocks
from autograder.pipeline.grades import GradeRow, all_graded_labs, read_grades, write_grades
from autograder.pipeline.intake import SUBMITTED, class_list, graded_from, import_submissions, not_student_ids
from autograder.pipeline.nbgrader_apps import course_config, feedback_page, generate_release, gradebook_url, run_app
from autograder.pipeline.shards import Shard
from autograder.pipeline.table import print_table
from course.checks import count


def check_reference_available(labs: list[Lab]) -> None:
    """Refuse to grade unless this process, where the hidden tests compare, imports every hidden test
    of these labs and the reference they use.

    Raises ReferenceUnavailable (from autograder.pipeline.hidden_blocks) if it cannot.
    """
    course_config()  # loading it puts the course root on this process's path, as for plain nbgrader
    for lab in labs:
        for test in hidden_blocks.hidden_tests(cells.read(lab.source_notebook)).values():
            test.load()


def sandbox_line() -> str:
    """What confines the grading kernels on this machine, as the grader's output says it (loudly if
    they are not fully sandboxed)."""
    status = sandbox.status()
    if status.complete:
        return f"Grading kernels are sandboxed: {status.summary}."
    return (f"WARNING: {status.summary}. The hidden tests still compare outside the kernel, so no answer can be "
            "forged, but see README (The grading kernel's sandbox) for what a kernel can reach here.")


def _grade_student(workdir: Path, lab_id: str, student: str, submitted: str) -> tuple[str, bool, bool]:
    """Autograde (from the folder ``submitted`` of ``workdir``), then write the feedback of, one student's
    submission of a lab, under that submission's lock (another shard grading it waits): nbgrader's log, and
    whether the graded notebook and the feedback page were there when the lock was let go. (Read after it, they can be missing only because an
    overlapping shard is grading the submission again: that is no failure of this run.)"""
    log = []
    lab = Lab(lab_id)
    with shards.gradebook_lock(gradebook_url(workdir), shards.submission_lock_name(lab_id, student)):
        for app_class in (Autograde, GenerateFeedback):
            result = run_app(app_class, workdir, lab, student, submitted)
            log.append(result.get("log", "") + result.get("error", ""))
        graded = (workdir / "autograded" / student / lab_id / lab.notebook_name).exists()
        page = feedback_page(workdir, lab_id, student).exists()
    return "".join(log), graded, page


def autograde(by_lab: dict[str, list[str]], workdir: Path, jobs: int | None = None,
              submitted: str = SUBMITTED) -> tuple[dict[str, str], set[tuple[str, str]], set[tuple[str, str]]]:
    """``nbgrader autograde`` and feedback for the submissions in ``workdir``: lab id -> students,
    read from its folder ``submitted`` (``intake.graded_from``).

    With ``jobs > 1`` (default: one per core) the submissions are graded that many at a time in
    separate processes, which all write to the one gradebook (SQLite waits for its lock; a database
    server handles it natively). A progress bar (tqdm, on stderr) counts the graded submissions.
    nbgrader goes on past a submission it cannot grade; that is not raised here, so that one bad
    file does not stop a class: the caller finds the submissions missing from the gradebook.
    Returns nbgrader's log of each lab, the (student, lab) graded, and those whose feedback page was written.
    """
    jobs = jobs or default_jobs()
    tasks = [(lab_id, student) for lab_id, students in by_lab.items() for student in students]
    logs: dict[tuple[str, str], str] = {}
    graded: set[tuple[str, str]] = set()
    pages: set[tuple[str, str]] = set()

    def record(lab_id: str, student: str, outcome: tuple[str, bool, bool]) -> None:
        logs[lab_id, student] = outcome[0]
        if outcome[1]:
            graded.add((student, lab_id))
        if outcome[2]:
            pages.add((student, lab_id))
    with tqdm(total=len(tasks), desc="Grading", unit="submission", file=sys.stderr, dynamic_ncols=True) as bar:
        if jobs <= 1 or len(tasks) <= 1:
            for lab_id, student in tasks:
                record(lab_id, student, _grade_student(workdir, lab_id, student, submitted))
                bar.update()
        else:
            with ProcessPoolExecutor(min(jobs, len(tasks)), mp_context=multiprocessing.get_context("spawn")) as pool:
                futures = {pool.submit(_grade_student, workdir, lab_id, student, submitted): (lab_id, student)
                           for lab_id, student in tasks}
                for future in as_completed(futures):
                    record(*futures[future], future.result())
                    bar.update()
    return ({lab_id: "".join(logs[lab_id, student] for student in students) for lab_id, students in by_lab.items()},
            graded, pages)


def set_up(labs: list[Lab], workdir: Path, by_lab: dict[str, list[str]]) -> None:
    """Set the class up in the course ``workdir`` and its gradebook, one process at a time (the
    gradebook's SET_UP lock, which holds across machines): ``nbgrader generate_assignment`` of each
    lab, the due dates, and a row for each student and submission of ``by_lab`` (lab id -> students)."""
    workdir.mkdir(parents=True, exist_ok=True)
    config = course_config(workdir)
    with shards.gradebook_lock(gradebook_url(workdir), shards.SET_UP):
        generate_release(labs, workdir)
        late.set_due_dates(labs, config)
        shards.register_class(gradebook_url(workdir), config.CourseDirectory.course_id, by_lab)


class SandboxIncomplete(RuntimeError):
    """``grade --require-sandbox`` where the grading kernels would not get every layer of the sandbox."""


@dataclass(frozen=True)
class Graded:
    """What ``grade`` did: the rows it wrote, and what it was given but did not grade."""

    rows: list[GradeRow]
    not_graded: list[tuple[str, str]]
    """(student, lab) of each submission that could not be graded (nbgrader's log says why)."""
    skipped: list[str]
    """The folders skipped because they are not named by a student id."""

    def problems(self) -> str:
        """One line that counts what was given and not graded, and why; empty when everything was graded."""
        parts = ([f"{count(len(self.not_graded), 'submission')} could not be graded (see the logs named above)"]
                 if self.not_graded else [])
        parts += [f"{count(len(self.skipped), 'folder')} not named by a student id"] if self.skipped else []
        return "; ".join(parts)


def grade(submissions: Path, workdir: Path = ROOT, out_csv: Path | None = None, jobs: int | None = None,
          shard: Shard | None = None, require_sandbox: bool = False) -> Graded:
    """Autograde ``submissions/<student>/<lab>/<lab>.ipynb`` in the course ``workdir``.

    Refuses to start unless this process can import the hidden tests and the reference, and skips
    (saying so) a student folder not named by a student id. Grades only the
    submissions given (with ``jobs`` processes), so that regrading one student leaves everyone
    else's grades as they were; with ``shard``, only that shard's students' (README: Large classes),
    into a PostgreSQL gradebook (else it raises shards.NotShared).
    Writes feedback HTML to ``workdir/feedback/`` and the grades of every graded submission in the
    course (a shard's: its own) to ``out_csv`` (default ``workdir/grades.csv``, a shard's
    ``workdir/grades-shard-K-of-N.csv``), prints the table, writes the class report (not for a shard:
    ``report`` after ``export``), and returns the rows, with what it did not grade. With ``require_sandbox``,
    refuses to start (SandboxIncomplete) unless the grading kernels get every layer of the sandbox. With a
    PostgreSQL gradebook, refuses to start (shards.TooFewConnections) unless its server accepts the
    connections that grading will open.
    """
    if require_sandbox and not sandbox.status().complete:
        raise SandboxIncomplete(f"{sandbox.status().summary}: grading refuses to start without the whole sandbox "
                                "(--require-sandbox). README: The grading kernel's sandbox says what each layer needs.")
    if shard is not None:
        shards.require_server(gradebook_url(workdir))
    known = {p.parent.name for p in (ROOT / "source").glob("*/*.ipynb")}
    for folder in sorted(p for p in submissions.glob("*/*") if p.is_dir() and p.name not in known):
        print(f"Skipped {folder}: there is no lab called {folder.name}.")
    labs = [Lab(lab_id) for lab_id in sorted(known & {p.name for p in submissions.glob("*/*") if p.is_dir()})]
    rejected = not_student_ids(submissions, labs)
    for line in rejected:
        print(f"Skipped: {line}")
    check_reference_available(labs)
    exposed = private_paths.exposed(ROOT, workdir)
    if exposed:
        print(private_paths.warning(exposed))
    print(sandbox_line())
    whole_class = class_list(submissions, labs)
    if shards.is_server(gradebook_url(workdir)):
        given = sum(shard is None or shard.takes(s) for students in whole_class.values() for s in students)
        shards.require_connections(gradebook_url(workdir), max(1, min(jobs or default_jobs(), given)))
    print(f"Setting up the course folder {workdir} for {count(len(labs), 'lab')} (nbgrader generate_assignment).")
    set_up(labs, workdir, whole_class)
    by_lab = import_submissions(submissions, workdir, labs, shard.takes if shard else None)
    if shard is not None:
        print(f"Shard {shard} grades {count(sum(map(len, by_lab.values())), 'submission')} of the class's "
              f"{sum(map(len, whole_class.values()))}.")
    logs, graded, written = autograde(by_lab, workdir, jobs, graded_from(submissions, workdir))
    if shard is None:
        rows = read_grades(workdir, all_graded_labs(workdir))
    else:
        rows = read_grades(workdir, labs, sorted({s for students in by_lab.values() for s in students}))
    failures = {lab.id: [s for s in by_lab[lab.id] if (s, lab.id) not in graded] for lab in labs}
    for lab in labs:
        pages = [s for s in by_lab[lab.id] if (s, lab.id) in graded and (s, lab.id) not in written]
        if failures[lab.id] or pages:
            log_path = workdir / f"autograde-{lab.id}{shard.suffix if shard else ''}.log"
            log_path.write_text(logs[lab.id])
        if failures[lab.id]:
            print(f"{count(len(failures[lab.id]), 'submission')} of {lab.id} could not be graded; "
                  f"nbgrader's log is in {log_path}.")
        if pages:
            print(f"No feedback page was written for {count(len(pages), 'graded submission')} of {lab.id}; "
                  f"nbgrader's log is in {log_path}.")
    out_csv = out_csv or workdir / f"grades{shard.suffix if shard else ''}.csv"
    write_grades(rows, out_csv)
    print_table(rows, failures)
    if rejected:
        print(f"Not graded: {count(len(rejected), 'folder')} not named by a student id (listed above).")
    print(f"Grades: {out_csv}. Feedback: {workdir / 'feedback'}.")
    if shard is None:
        for page in class_report.write_report(workdir, rows):
            print(f"Class report: {page}")
    else:
        print(f"When every shard is done: `python -m autograder export --workdir {workdir}` writes the class's "
              "grades.csv and lists any submission not graded yet, and `python -m autograder report --workdir "
              f"{workdir}` the class report.")
    return Graded(rows, [(s, lab_id) for lab_id, students in failures.items() for s in students], rejected)

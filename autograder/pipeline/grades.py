"""Reading the grades back from the gradebook, and writing grades.csv with the record of the
grading environment beside it."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import nbformat
from nbgrader.api import Gradebook, MissingEntry
from nbgrader.coursedir import CourseDirectory

from autograder import cells, csv_cells
from autograder.integrity.flag import FLAG
from autograder.labs import ROOT, Lab
from autograder.pipeline import verdicts, versions
from autograder.pipeline.nbgrader_apps import course_config
from autograder.pipeline.restore import GraderNote, NoteKind, grader_notes
from course.checks import NOT_WRITTEN


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
    """Points taken for a late submission (nbgrader's AssignLatePenalties, autograder/pipeline/late.py)."""
    notes: tuple[GraderNote, ...] = ()
    """The grader's notes in the feedback: what it changed to grade, the cell whose failure the errors below
    follow from, and its flags for review (``restore.NoteKind``)."""
    reasons: dict[str, str] = field(default_factory=dict)
    """Why each autograded cell short of full marks lost them: its error, or its stderr output."""
    diagnosed: dict[str, str] = field(default_factory=dict)
    """Test cell -> slug of the catalogued mistake its failing hidden test was diagnosed as, for each
    cell short of full marks whose failure was diagnosed (recorded by the grader, verdicts.DIAGNOSIS_KEY)."""
    not_written: frozenset[str] = frozenset()
    """The test cells whose blank still holds the stub it was released with (never written)."""
    wrong_only: dict[str, str] = field(default_factory=dict)
    """Test cell -> the kind of case that alone its failing hidden test was wrong on, for each cell short
    of full marks where a property split the cases exactly (recorded by the grader, verdicts.WRONG_ONLY_KEY)."""
    visible_failed: frozenset[str] = frozenset()
    """The test cells whose blank's visible checks failed in the grading run (recorded by the grader,
    verdicts.VISIBLE_CHECK_KEY): for the class report, never part of a score."""

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
        return [note.text.removeprefix(FLAG).strip() for note in self.notes if note.kind == NoteKind.FLAG]

    @property
    def changes(self) -> list[str]:
        """What the grader changed to grade the submission (a fault it handled: a stopped cell, restored cells)."""
        return [note.text for note in self.notes if note.kind == NoteKind.CHANGE]

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
                notes, reasons, diagnosed, wrong_only, not_written, visible_failed = _read_autograded(autograded, lab)
                lost = {c for c in order if (cells[c] or 0.0) < maxima[c]}
                rows.append(
                    GradeRow(
                        student,
                        lab.id,
                        {c: cells[c] for c in order},
                        {c: maxima[c] for c in order},
                        frozenset(auto),
                        submission.late_submission_penalty or 0.0,
                        notes,
                        {c: reasons[c] for c in order if c in reasons and c in lost},
                        {c: diagnosed[c] for c in order if c in diagnosed and c in lost},
                        frozenset(not_written & auto),
                        {c: wrong_only[c] for c in order if c in wrong_only and c in lost},
                        frozenset(visible_failed & auto),
                    )
                )
    return rows


ANSI = re.compile(r"\x1b\[[0-9;]*m")


def _read_autograded(autograded: Path, lab: Lab) -> tuple[tuple[str, ...], dict[str, str], dict[str, str],
                                                          dict[str, str], set[str], set[str]]:
    """What an autograded notebook says beside the gradebook: the grader's notes; for each graded
    cell its first error (the grader's reason for a failing verdict, the only error a test cell
    holds, autograder/pipeline/verdicts.py); test cell -> diagnosed mistake (``verdicts.diagnoses``), and
    -> the kind of case alone wrong;
    the test cells of the blanks whose stub the hidden test called (as it ran: the cells' text can say otherwise,
    as reviews of issue 31 showed); and those of the blanks
    whose visible checks failed (``verdicts.visible_checks_failed``)."""
    nb = nbformat.read(autograded, as_version=4)
    reasons = {}
    for cell in nb.cells:
        if cell.cell_type != "code" or not cells.meta(cell).get("grade"):
            continue
        errors = [o for o in cell.outputs if o.output_type == "error"]
        if errors:
            reasons[cells.grade_id(cell)] = ANSI.sub("", f"{errors[0].ename}: {errors[0].evalue}")
    # the grader's hidden test called the stub, whatever the cells say: a blank defined in a cell added below its
    # untouched stub is the function called (an adversarial review of issue 31 hid a mistake so, with def, import
    # or match), and a stub with a comment added is still the stub (a final review)
    stub_called = f"NotImplementedError: {NOT_WRITTEN}"
    not_written = {f"test_{cells.grade_id(c)}" for c in nb.cells
                   if cells.is_code_answer(c) and reasons.get(f"test_{cells.grade_id(c)}", "").startswith(stub_called)}
    return (tuple(grader_notes(nb)), reasons, verdicts.diagnoses(nb), verdicts.diagnoses(nb, verdicts.WRONG_ONLY_KEY),
            not_written, verdicts.visible_checks_failed(nb))


def write_grades(rows: list[GradeRow], path: Path) -> None:
    """grades.csv (``write_csv``) and the record of the grading environment beside it (``versions.record``)."""
    write_csv(rows, path)
    versions.record(path)


def write_csv(rows: list[GradeRow], path: Path) -> None:
    """One row per student and lab, one column per graded cell (empty: not in this lab, or not
    graded by hand yet), the late penalty, the total so far (less the penalty), and the total possible.
    Text that a spreadsheet would read as a formula is neutralised (``csv_cells``)."""
    columns: list[str] = []
    for row in rows:
        columns += [c for c in row.cells if c not in columns]
    with open(path, "w", newline="") as handle:
        writer = csv_cells.writer(handle)
        writer.writerow(["student", "lab", *columns, "late_penalty", "total", "max_score", "flagged", "notes"])
        for row in rows:
            scores = ["" if row.cells.get(c) is None else f"{row.cells[c]:g}" for c in columns]
            notes = [n.text for n in row.notes if n.kind != NoteKind.FLAG] + [f"{c}: {why}" for c, why in row.reasons.items()]
            writer.writerow([row.student, row.lab, *scores, f"{row.late_penalty:g}", f"{row.total:g}",
                             f"{sum(row.max_cells.values()):g}", " | ".join(row.flags), " | ".join(notes)])

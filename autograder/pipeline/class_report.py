"""What a class got wrong, lab by lab: the counts of ``python -m autograder report``, and its files.

Each autograded test cell of each graded submission has one outcome: full marks; lost to a
catalogued mistake (the diagnosis the grader recorded as data while grading, ``GradeRow.diagnosed``,
never read back out of a message); lost another way (grouped by the kind of case that alone it was
wrong on, when the grader recorded one, ``GradeRow.wrong_only``, else by the name of the error that
failed it); or not written (its blank still holds the released stub). Per lab, the report also counts the
submissions flagged for review, late, and faulted (a grader's note of a change: a stopped
cell, a dead kernel, restored cells; not a flag, nor the note that only explains an error), the submissions handed in with a written blank whose visible
checks failed (per blank and in all, from the record the grader made while grading,
``GradeRow.visible_failed``: information, never part of a score), and the written answers still
waiting for a hand grade.

``write_report`` writes into ``COURSE/report/``, per lab: ``<lab>.html`` (counts only, for a
lecture: report_page.py), ``<lab>.png`` (report_figure.py), ``<lab>.csv`` (the counts) and
``<lab>-students.csv`` (the students behind each count, for the instructor). The counts themselves are
``LabCounts`` and ``BlankCounts`` (class_counts.py), which the page and the figure read too.
"""

from __future__ import annotations

from pathlib import Path

from autograder import csv_cells
from autograder.catalogues.mistakes import Mistake, catalogue
from autograder.labs import Lab
from autograder.pipeline import report_figure, report_page
from autograder.pipeline.class_counts import BlankCounts, LabCounts
from autograder.pipeline.grades import GradeRow

FULL, MISTAKE, OTHER, NOT_WRITTEN = "full marks", "catalogued mistake", "lost another way", "not written"
"""The outcomes of one test cell of one submission."""
FLAGGED_DETAIL = "in a submission flagged for review"
"""The detail of a blank lost in a flagged submission that no catalogued mistake explains."""
WRONG_ONLY = report_page.WRONG_ONLY_LEAD + " {}"
"""The detail of a blank lost another way, wrong on one kind of case alone ("a full R")."""
SUBMITTED, FLAGGED, LATE, FAULTED, WAITING, SCORE, VISIBLE_FAILED = (
    "graded", "flagged", "late", "faulted", "waiting for a hand grade", "autograded score", "visible checks failed")
"""The lab's other counts, as the CSVs name them."""


def _by_size(groups: dict[str, list[str]]) -> dict[str, tuple[str, ...]]:
    """Groups of students, the largest first (ties by name), each sorted."""
    return {key: tuple(sorted(students)) for key, students in sorted(groups.items(), key=lambda kv: (-len(kv[1]), kv[0]))}


def outcome(row: GradeRow, cell: str, mistakes: dict[tuple[str, str], Mistake]) -> tuple[str, str]:
    """The outcome of the test cell ``cell`` in ``row``, and its detail: the mistake's slug, or the
    kind of case that alone it was wrong on, or the failing error's name (a slug the lab does not
    catalogue counts as lost another way)."""
    if (row.cells[cell] or 0.0) >= row.max_cells[cell]:
        return FULL, ""
    slug = row.diagnosed.get(cell)
    if slug is not None and (cell.removeprefix("test_"), slug) in mistakes:
        return MISTAKE, slug  # the grader's diagnosis, before anything read from the submission's cells
    if cell in row.not_written:
        return NOT_WRITTEN, ""
    if row.flags:  # the scan's flag zeroes the blanks a finding games: the error then says nothing of the cause
        return OTHER, FLAGGED_DETAIL
    if cell in row.wrong_only:
        return OTHER, WRONG_ONLY.format(row.wrong_only[cell])
    return OTHER, row.reasons.get(cell, "no reason recorded").partition(":")[0].strip()


def _visible_failed(row: GradeRow, cell: str) -> bool:
    """Whether ``row``'s student wrote the blank of the test cell ``cell`` and its visible checks failed."""
    return cell in row.visible_failed and cell not in row.not_written


def count_lab(lab: Lab, rows: list[GradeRow]) -> LabCounts:
    """The counts of ``lab`` from its graded ``rows`` (GradeRows of other labs are left out)."""
    rows = sorted((r for r in rows if r.lab == lab.id), key=lambda r: r.student)
    mistakes = {(m.blank, m.slug): m for m in catalogue(lab)}
    first = rows[0] if rows else None
    tests = [c for c in first.cells if c in first.autograded] if first else []
    blanks = []
    for cell in tests:
        groups: dict[tuple[str, str], list[str]] = {}
        for row in rows:
            groups.setdefault(outcome(row, cell, mistakes), []).append(row.student)
        of = lambda kind: _by_size({detail: s for (k, detail), s in groups.items() if k == kind})  # noqa: E731
        blanks.append(BlankCounts(cell, tuple(sorted(groups.get((FULL, ""), []))), of(MISTAKE), of(OTHER),
                                  tuple(sorted(groups.get((NOT_WRITTEN, ""), []))),
                                  tuple(row.student for row in rows if _visible_failed(row, cell))))
    written = [c for c in first.cells if c not in first.autograded] if first else []
    return LabCounts(
        lab.id,
        {row.student: row.auto_score for row in rows},
        first.auto_max if first else 0.0,
        tuple(blanks),
        tuple(row.student for row in rows if row.flags),
        tuple(row.student for row in rows if row.late_penalty > 0),
        tuple(row.student for row in rows if row.changes),
        tuple(row.student for row in rows if any(_visible_failed(row, cell) for cell in tests)),
        {cell: tuple(row.student for row in rows if row.cells.get(cell) is None) for cell in written},
        mistakes,
    )


def entries(counts: LabCounts) -> list[tuple[str, str, str, tuple[str, ...]]]:
    """Every count of the lab as (cell, what, detail, students): the rows of both CSVs."""
    found: list[tuple[str, str, str, tuple[str, ...]]] = [("", SUBMITTED, "", counts.students)]
    found += [("", SCORE, label, students) for label, students in counts.score_bins()]
    for blank in counts.blanks:
        found.append((blank.cell, FULL, "", blank.full))
        found += [(blank.cell, MISTAKE, slug, students) for slug, students in blank.mistakes.items()]
        found += [(blank.cell, OTHER, name, students) for name, students in blank.other.items()]
        found.append((blank.cell, NOT_WRITTEN, "", blank.not_written))
        found.append((blank.cell, VISIBLE_FAILED, "", blank.visible_failed))
    found += [("", FLAGGED, "", counts.flagged), ("", LATE, "", counts.late), ("", FAULTED, "", counts.faulted),
              ("", VISIBLE_FAILED, "", counts.visible_failed)]
    found += [(cell, WAITING, "", students) for cell, students in counts.waiting.items()]
    return found


def write_csvs(counts: LabCounts, folder: Path) -> tuple[Path, Path]:
    """``folder/<lab>.csv`` (one row per count) and ``folder/<lab>-students.csv`` (one row per
    student behind a count), through csv_cells, which neutralises formulas."""
    counts_path, students_path = folder / f"{counts.lab}.csv", folder / f"{counts.lab}-students.csv"
    found = entries(counts)
    with open(counts_path, "w", newline="") as handle:
        writer = csv_cells.writer(handle)
        writer.writerow(["lab", "cell", "what", "detail", "count"])
        for cell, what, detail, students in found:
            writer.writerow([counts.lab, cell, what, detail, len(students)])
    with open(students_path, "w", newline="") as handle:
        writer = csv_cells.writer(handle)
        writer.writerow(["lab", "cell", "what", "detail", "student"])
        for cell, what, detail, students in found:
            for student in students:
                writer.writerow([counts.lab, cell, what, detail, student])
    return counts_path, students_path


def page_path(workdir: Path, lab_id: str) -> Path:
    """Where the class report's page of ``lab_id`` is written for the course ``workdir``."""
    return workdir / "report" / f"{lab_id}.html"


def write_report(workdir: Path, rows: list[GradeRow]) -> list[Path]:
    """Write the class report of every lab in ``rows`` into ``workdir/report/``; the HTML pages."""
    folder = workdir / "report"
    folder.mkdir(parents=True, exist_ok=True)
    pages = []
    for lab_id in sorted({row.lab for row in rows}):
        counts = count_lab(Lab(lab_id), rows)
        write_csvs(counts, folder)
        figure = report_figure.draw(counts, folder / f"{lab_id}.png")
        pages.append(report_page.write(counts, figure, page_path(workdir, lab_id)))
    return pages



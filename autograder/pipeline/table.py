"""The summary table that ``grade`` prints: one line per submission, then why each lost cell lost
its points, at most 100 columns wide."""

from __future__ import annotations

import re
import shutil
import textwrap

from autograder.pipeline.grades import GradeRow

TABLE_WIDTH = 100
"""The widest the summary table gets, in characters (narrower if the terminal is)."""
CONTROL = re.compile(r"[\x00-\x09\x0b-\x1f\x7f-\x9f]")
"""Every control character but the newline: ESC and CSI begin the terminal's escape sequences (move the
cursor, erase a line, set the window's title or the clipboard, make a link), which a submission's error
message could hold; the table prints none of them, whatever a message says."""


def _lost_lines(row: GradeRow) -> list[str]:
    """Each lost cell once, with why it lost its points; cells that lost them for the same reason share a line."""
    by_reason: dict[str, list[str]] = {}
    for cell in row.lost:
        by_reason.setdefault(row.reasons.get(cell, "no reason was recorded"), []).append(cell)
    return [f"{', '.join(lost)}: {reason}" for reason, lost in by_reason.items()]


def format_table(rows: list[GradeRow], failures: dict[str, list[str]] | None = None, width: int | None = None) -> str:
    """The summary table: one line per submission (student, lab, autograded score, what happened, and for a
    late one its total after the penalty, as grades.csv has it), then its late penalty, the grader's notes and each lost cell with its reason, wrapped to ``width`` columns
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
        if row.late_penalty:  # the score is before the penalty: the row itself says so, not only the line below
            result += f"; late, total {row.total:g}"
        lines += line(row.student, row.lab, f"{row.auto_score:g}/{row.auto_max:g}", result)
        late = ([f"Late: a penalty of {row.late_penalty:g} points, so its total is {row.total:g} (grades.csv's total)."]
                if row.late_penalty else [])
        for text in [*late, *(note.text for note in row.notes), *_lost_lines(row)]:
            lines += textwrap.wrap(" ".join(text.split()), width, initial_indent=indent, subsequent_indent=indent + "  ",
                                   max_lines=3, placeholder=" ...", break_on_hyphens=False)
    for lab_id, students in (failures or {}).items():
        for student in students:
            lines += line(student, lab_id, "-", "not graded: see the log")
    lines.append("-" * width)
    lines += textwrap.wrap("Scores count the autograded cells only: written answers are graded by hand in formgrader.", width)
    return CONTROL.sub("", "\n".join(lines))


def print_table(rows: list[GradeRow], failures: dict[str, list[str]] | None = None) -> None:
    """Print ``format_table``."""
    print(format_table(rows, failures))

"""The demo: make a synthetic class from the committed release, grade it, print the table, and say
whether every row came out as the catalogues say it must (`python -m autograder release` regenerates
the release; a test keeps the committed one current).

The default class is small, so that a first run shows the kit working in a few minutes: for each
lab a blank submission, the solved one, a few catalogued mistakes in different blanks, one cheat and
one careless fault. ``full=True`` grades the whole catalogue instead: blank, solved and every
catalogued mistake of every lab.
"""

from __future__ import annotations

import shutil
import textwrap
from pathlib import Path

from autograder import cells
from autograder.catalogues import cheats, faults, submissions
from autograder.pipeline import class_report, grading, grades, nbgrader_apps, table
from autograder.labs import ROOT, Lab, all_labs
from autograder.catalogues.mistakes import catalogue
from autograder.catalogues.synthetic_class import (MISTAKE, Outcome, cheat_outcome, fault_outcome, honest_outcome,
                                                   write_honest)
from course.checks import count

DEMO_DIR = ROOT / "demo"
QUICK_MISTAKES = 2
"""Catalogued mistakes per lab in the quick class, each in a different blank."""
QUICK_CHEAT = "import-reference"
QUICK_FAULT = "numpy-warning"


def _honest(lab: Lab, folder: Path, mistakes) -> list[Outcome]:
    """Write the blank and solved submissions and one per mistake of ``lab``; their outcomes."""
    submissions.write(submissions.solved(lab), folder, submissions.SOLVED, lab)
    submissions.write(cells.read(lab.release_notebook), folder, submissions.BLANK, lab)
    outcomes = [Outcome(submissions.BLANK, "blank", None, only=False, flagged=False),
                honest_outcome(submissions.SOLVED, None)]
    for mistake in mistakes:
        submissions.write(submissions.with_mistake(lab, mistake), folder, mistake.student_id(lab), lab)
        outcomes.append(honest_outcome(mistake.student_id(lab), mistake))
    return outcomes


def quick_mistakes(lab: Lab, size: int = QUICK_MISTAKES) -> list:
    """``size`` catalogued mistakes of ``lab``, each in a different blank, spread over the lab."""
    first = {}
    for mistake in catalogue(lab):
        first.setdefault(mistake.blank, mistake)
    blanks = list(first)
    return [first[blanks[round(k * (len(blanks) - 1) / max(size - 1, 1))]] for k in range(min(size, len(blanks)))]


def write_demo_class(labs: list[Lab], folder: Path, full: bool = False,
                     size: int | None = None) -> dict[tuple[str, str], Outcome]:
    """Write the demo class as ``folder/<student>/<lab>/...``: (student, lab id) -> what grading must make of it.
    With ``size``, honest work (``synthetic_class.write_honest``) then fills each lab up to ``size`` submissions."""
    if folder.exists():
        shutil.rmtree(folder)
    expected: dict[tuple[str, str], Outcome] = {}
    for lab in labs:
        outcomes = _honest(lab, folder, catalogue(lab) if full else quick_mistakes(lab))
        if not full:
            cheat = cheats.get(QUICK_CHEAT)
            submissions.write(cheat.notebook(lab), folder, cheat.name, lab)
            fault = faults.get(QUICK_FAULT)
            blank = cells.blank_names(cells.read(lab.source_notebook))[0]
            faults.write_fault(fault, lab, blank, folder)
            outcomes += [cheat_outcome(lab, cheat), fault_outcome(lab, fault, blank)]
        if size is not None:
            outcomes += write_honest(lab, size - len(outcomes), folder)
        expected |= {(o.student, lab.id): o for o in outcomes}
    return expected


def unexpected(rows: list[grades.GradeRow], expected: dict[tuple[str, str], Outcome]) -> list[str]:
    """How the graded ``rows`` differ from what the catalogues say (empty: every row as expected)."""
    by_key = {(row.student, row.lab): row for row in rows}
    found = []
    for (student, lab_id), outcome in expected.items():
        row = by_key.get((student, lab_id))
        found += [f"{lab_id}: {error}" for error in outcome.errors(row)] if row else [f"{lab_id}: {student} was not graded"]
    return found


def run_demo(workdir: Path = DEMO_DIR, jobs: int | None = None, full: bool = False) -> bool:
    """Write the demo class to ``workdir/class``, grade it in a new ``workdir/course``
    with ``jobs`` processes (default: one per core), and print whether every row came out as
    expected and where to look next. Returns whether every row did."""
    labs = all_labs()
    class_dir, course, grades_csv = workdir / "class", workdir / "course", workdir / "grades.csv"
    expected = write_demo_class(labs, class_dir, full)
    if course.exists():  # a new gradebook, so that the table holds this class and nothing else
        shutil.rmtree(course)
    students = {student for student, _ in expected}
    kinds = ("blank, solved and every catalogued mistake" if full else
             f"blank, solved, {QUICK_MISTAKES} catalogued mistakes, one cheat and one careless fault")
    print(textwrap.fill(f"Demo class: {count(len(expected), 'submission')} of {count(len(labs), 'lab')} from "
                        f"{count(len(students), 'student')} in {class_dir} ({kinds} per lab).", table.TABLE_WIDTH,
                        break_on_hyphens=False, break_long_words=False))
    rows = grading.grade(class_dir, course, grades_csv, jobs).rows
    differ = unexpected(rows, expected)
    if differ:
        print(f"Not as expected: {count(len(differ), 'difference')} between the grades and the catalogues:")
        for line in differ:
            print(textwrap.fill(line, table.TABLE_WIDTH, initial_indent="  - ", subsequent_indent="    "))
    else:
        print(textwrap.fill(f"All {count(len(expected), 'row')} came out as expected: the blank scores 0, the solved "
                            "notebook full marks, each mistake, cheat and fault loses what its catalogue says, and "
                            "only the cheats that the integrity checks catch are flagged.", table.TABLE_WIDTH))
    example = next((s for (s, lab), o in expected.items() if o.kind == MISTAKE), submissions.SOLVED)
    example_lab = next(lab for (s, lab) in expected if s == example)
    def shown(path: Path) -> Path:  # relative to the course root, where the commands run
        return path.relative_to(ROOT) if path.is_relative_to(ROOT) else path

    root = shown(course)
    steps = [  # what to look at, and where (a path or a command, on a line of its own to copy)
        ("The grades, one row per submission:", [str(shown(grades_csv))]),
        ("One student's feedback page:", [str(shown(nbgrader_apps.feedback_page(course, example_lab, example)))]),
        ("The class report, what the class got wrong (a page per lab, with its figure and counts beside it):",
         [str(shown(class_report.page_path(course, lab.id))) for lab in labs]),
        (f"The written answers, to grade by hand: from {ROOT}, start JupyterLab on the demo's course and open "
         "Nbgrader > Formgrader > Manual Grading; then rewrite the feedback pages and the grades:",
         [f".venv/bin/jupyter lab --CourseDirectory.root={root}", f".venv/bin/python -m autograder feedback --workdir {root}"]),
    ]
    if not full:
        whole = sum(len(catalogue(lab)) + 2 for lab in labs)  # blank, solved and every mistake
        steps.append((f"The whole catalogue ({count(whole, 'submission')}, {whole / len(expected):.0f} times as many as here):",
                      [".venv/bin/python -m autograder demo --full"]))
    print("Where to look next:")
    for text, lines in steps:
        print(textwrap.fill(text, table.TABLE_WIDTH, initial_indent="  - ", subsequent_indent="    ",
                            break_on_hyphens=False, break_long_words=False))
        for line in lines:
            print(f"      {line}")
    return not differ

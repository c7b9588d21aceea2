"""A synthetic class of one lab that mixes every kind of submission, and what grading must make of each.

A class holds every catalogued fault (careless work: stuck, crashing, memory-hungry, unreadable...),
every catalogued cheat (hostile work), then the solved notebook and the catalogued mistakes in turn
(honest work) until it has ``size`` submissions. Each submission comes with its ``Outcome``, so a
graded class can be checked against the catalogues: the throughput benchmark grades 200 per lab and
checks every row, and tests/test_cheating_graded.py uses the same rule for the cheats.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from pathlib import Path

from autograder import cells
from autograder.catalogues import cheats, faults, submissions
from autograder.catalogues.cheats import STATIC, Cheat, target
from autograder.pipeline.grading import GradeRow
from autograder.labs import Lab
from autograder.catalogues.mistakes import Mistake, catalogue as mistake_catalogue

FAULT, CHEAT, MISTAKE, SOLVED = "fault", "cheat", "mistake", "solved"


@dataclass(frozen=True)
class Outcome:
    """What grading must make of one submission."""

    student: str
    kind: str
    """FAULT, CHEAT, MISTAKE or SOLVED."""
    zero: tuple[str, ...] | None
    """The test cells that must score 0; None: every autograded cell."""
    only: bool
    """Every other autograded cell must keep full marks."""
    flagged: bool
    """Whether the submission must be flagged for review (it must not be otherwise)."""
    mistake: str = ""
    """A MISTAKE's slug in its blank's catalogue."""

    def errors(self, row: GradeRow) -> list[str]:
        """How ``row`` differs from this outcome (empty: it is as catalogued)."""
        zero = sorted(row.autograded) if self.zero is None else list(self.zero)
        errors = [f"{test} scored {row.cells[test]}, not 0" for test in zero if row.cells[test] != 0]
        if self.only:
            errors += [f"{test} lost marks ({row.reasons.get(test, 'no reason')})" for test in row.lost if test not in zero]
        if bool(row.flags) != self.flagged:
            errors.append(f"flagged: {row.flags}" if row.flags else "not flagged")
        return [f"{self.student}: {error}" for error in errors]


def cheat_outcome(lab: Lab, cheat: Cheat) -> Outcome:
    """A cheat gains nothing. One that the scan catches is flagged and loses every blank it games
    (where the scan's finding costs nothing, the grader's comparison fails the blank it aims at);
    the others (defeated by the grader's comparison, the sandbox, the sanitize step or the hidden
    tests' random inputs) are not flagged and lose the blank they tried to pass with a wrong answer."""
    if STATIC in cheat.caught_by and not cheat.scan_costs:
        return Outcome(cheat.name, CHEAT, (f"test_{cheat.aim or target(lab)}",), only=False, flagged=True)
    if STATIC in cheat.caught_by:
        gamed = cheat.blanks(lab)
        return Outcome(cheat.name, CHEAT, None if gamed is None else tuple(f"test_{b}" for b in gamed),
                       only=False, flagged=True)
    wrong = cheat.aim or target(lab) if cheat.plants_mistake or cheat.games == "blank" else None
    return Outcome(cheat.name, CHEAT, () if wrong is None else (f"test_{wrong}",), only=False, flagged=False)


def honest_outcome(student: str, wrong: Mistake | None) -> Outcome:
    """The solved notebook (``wrong`` None), or the catalogued mistake ``wrong``, which loses its
    blank's test and nothing else; neither is flagged."""
    if wrong is None:
        return Outcome(student, SOLVED, (), only=True, flagged=False)
    return Outcome(student, MISTAKE, (f"test_{wrong.blank}",), only=True, flagged=False, mistake=wrong.slug)


def fault_outcome(lab: Lab, fault: faults.Fault, blank: str) -> Outcome:
    """A fault in ``blank`` costs what the catalogue says and nothing else; it is never flagged."""
    zero = {faults.ALL: None, "blank": (f"test_{blank}",), None: ()}[fault.loses]
    return Outcome(fault.student_id(lab), FAULT, zero, only=True, flagged=False)


def write(lab: Lab, size: int, folder: Path) -> list[Outcome]:
    """Write a class of ``size`` submissions of ``lab`` as ``folder/<student>/<lab>/...``; their outcomes."""
    hostile = len(faults.FAULTS) + len(cheats.catalogue(lab))
    if size < hostile:
        raise ValueError(f"a class of {lab.id} needs at least {hostile} submissions: one per fault and per cheat")
    blank = cells.blank_names(cells.read(lab.source_notebook))[0]
    faults.write_faults(lab, blank, folder)
    outcomes = [fault_outcome(lab, fault, blank) for fault in faults.FAULTS]
    for cheat in cheats.catalogue(lab):
        submissions.write(cheat.notebook(lab), folder, cheat.name, lab)
        outcomes.append(cheat_outcome(lab, cheat))
    return outcomes + write_honest(lab, size - len(outcomes), folder)


def write_honest(lab: Lab, size: int, folder: Path) -> list[Outcome]:
    """Write ``size`` honest submissions of ``lab``, the solved notebook and each catalogued mistake
    in turn, as the students ``student000``, ``student001``, ...; their outcomes."""
    honest = itertools.cycle([(submissions.solved(lab), None)]
                             + [(submissions.with_mistake(lab, m), m) for m in mistake_catalogue(lab)])
    outcomes = []
    for k in range(size):
        nb, wrong = next(honest)
        submissions.write(nb, folder, f"student{k:03d}", lab)
        outcomes.append(honest_outcome(f"student{k:03d}", wrong))
    return outcomes


def errors(rows: list[GradeRow], outcomes: list[Outcome]) -> dict[str, list[str]]:
    """The students whose graded rows differ from their ``outcomes``, and how (a missing row is one way)."""
    by_student = {row.student: row for row in rows}
    found = {o.student: o.errors(by_student[o.student]) if o.student in by_student else [f"{o.student}: no grade"]
             for o in outcomes}
    return {student: errs for student, errs in found.items() if errs}

"""What each lab holds: blanks, points, visible checks, hidden tests and catalogued mistakes."""

from __future__ import annotations

import ast
import textwrap
from collections import Counter
from dataclasses import dataclass

from autograder import cells
from autograder.authoring import claims, mutants, visible_checks
from autograder.catalogues.alternatives import catalogue as alternative_catalogue
from autograder.labs import Lab
from autograder.catalogues.mistakes import catalogue
from course.checks import count

CHECK_HELPERS = {"check_array", "check_close", "check_pair", "check_symmetric", "check_true"}


@dataclass(frozen=True)
class Inventory:
    lab: str
    blanks: int
    """Blanks, each with its hidden test (check_<blank>, over several random cases)."""
    blank_points: dict[str, float]
    """Each blank's name -> the points of its hidden test, in the notebook's order."""
    blank_mistakes: dict[str, int]
    """Each blank's name -> how many catalogued mistakes it has."""
    autograded_points: float
    written_answers: int
    written_points: float
    visible_checks: int
    """Calls of the course.checks helpers in the visible-check cells."""
    hidden_assertions: int
    """Check-helper calls that the hidden tests make when they grade the reference."""
    mistakes: int
    claims: dict[str, str]
    """Claim id -> what its check verifies, for every claim the lab's text marks."""
    blank_alternatives: dict[str, int]
    """Each blank's name -> how many correct alternatives its bank holds."""
    visible_caught: tuple[int, int, int]
    """(catalogued mistakes that the visible checks fail, those of them whose message names the fix, catalogued
    mistakes)."""
    mutation: mutants.Report
    """The mutants of the reference's blanks: killed by the hidden tests, equivalent, surviving."""


def _helper_calls(code: str) -> int:
    return sum(
        1
        for node in ast.walk(ast.parse(code))
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in CHECK_HELPERS
    )


def _assertions_on_reference(lab: Lab, hidden, blanks: list[str]) -> int:
    """Run the hidden tests on the reference, counting the check-helper calls they make."""
    count = 0
    originals = {name: getattr(hidden, name) for name in CHECK_HELPERS if hasattr(hidden, name)}

    def counted(helper):
        def wrapper(*args, **kwargs):
            nonlocal count
            count += 1
            return helper(*args, **kwargs)

        return wrapper

    try:
        for name, helper in originals.items():
            setattr(hidden, name, counted(helper))
        for name in blanks:
            getattr(hidden, f"check_{name}")(getattr(lab.reference(), name))
    finally:
        for name, helper in originals.items():
            setattr(hidden, name, helper)
    return count


def inventory(lab: Lab) -> Inventory:
    nb = cells.read(lab.source_notebook)
    blanks = cells.blank_names(nb)
    points = {cells.grade_id(c): cells.meta(c)["points"] for c in nb.cells if cells.meta(c).get("grade")}
    written = [c for c in nb.cells if cells.is_answer(c) and c.cell_type == "markdown"]
    visible = [c for c in nb.cells if "nbgrader" in c.metadata and cells.grade_id(c).startswith("check_")]
    hidden = lab.hidden_module("hidden_tests")
    blank_points = {name: points[f"test_{name}"] for name in blanks}
    mistakes = Counter(m.blank for m in catalogue(lab))
    alternatives = Counter(a.blank for a in alternative_catalogue(lab))
    return Inventory(
        lab=lab.id,
        blanks=len(blanks),
        blank_points=blank_points,
        blank_mistakes={name: mistakes[name] for name in blanks},
        autograded_points=sum(blank_points.values()),
        written_answers=len(written),
        written_points=sum(points[cells.grade_id(c)] for c in written),
        visible_checks=sum(_helper_calls("\n".join(l for l in c.source.splitlines() if not l.startswith("%"))) for c in visible),
        hidden_assertions=_assertions_on_reference(lab, hidden, blanks),
        mistakes=sum(mistakes.values()),
        claims={cid: c.summary for cid, c in claims.checks(lab).items()},
        blank_alternatives={name: alternatives[name] for name in blanks},
        visible_caught=visible_checks.mistakes_caught(lab),
        mutation=mutants.report(lab),
    )


def print_inventory(labs: list[Lab]) -> None:
    """Print a summary line per lab, then each lab's blanks by name and the claims it checks."""
    header = ("lab", "blanks", "points", "written", "visible", "hidden", "mistakes", "claims")
    second = ("", "", "(auto)", "answers (pt)", "checks", "asserts", "", "")
    widths = (18, 7, 8, 13, 8, 8, 9, 7)

    def line(values) -> str:
        return "".join(f"{v:<{w}}" if k == 0 else f"{v:>{w}}" for k, (v, w) in enumerate(zip(values, widths)))

    print(line(header))
    print(line(second))
    inventories = [inventory(lab) for lab in labs]
    for i in inventories:
        print(line((i.lab, i.blanks, f"{i.autograded_points:g}", f"{i.written_answers} ({i.written_points:g})",
                    i.visible_checks, i.hidden_assertions, i.mistakes, len(i.claims))))
    for lab, i in zip(labs, inventories):
        print(f"\nThe blanks of {i.lab}, in order (hidden test's points, catalogued mistakes, correct alternatives):")
        name_w = max(len(name) for name in i.blank_points)
        for name, points in i.blank_points.items():
            mistakes = i.blank_mistakes[name]
            print(f"  {name:<{name_w}}  {points:>4g} pt  {count(mistakes, 'mistake'):<12}"
                  f"{count(i.blank_alternatives[name], 'alternative')}")
        print(f"Claims that {i.lab} states, each recomputed by a check (solutions/{lab.module}/claims.py):")
        for cid, summary in i.claims.items():
            print(textwrap.fill(f"{cid}: {summary}", 100, initial_indent="  ", subsequent_indent="      ",
                                break_on_hyphens=False))
        caught, fixed, mistakes = i.visible_caught
        m = i.mutation
        print(textwrap.fill(
            f"Right both ways: the visible checks fail {caught} of the {count(mistakes, 'catalogued mistake')} "
            f"({caught / max(mistakes, 1):.0%}), and the message names the fix (the check's hint) for {fixed} of them "
            f"({fixed / max(mistakes, 1):.0%} of the mistakes). Mutants of the reference (autograder/authoring/mutants.py): {m.mutants}, "
            f"of which the hidden tests kill {m.killed}, {m.equivalent} are listed as equivalent "
            f"(solutions/{lab.module}/mutants.py) and {len(m.surviving)} survive; the message of {m.narrowed} "
            f"of the {m.killed} killed ({m.narrowed / max(m.killed, 1):.0%}) narrows the cause (the kinds of case it is "
            f"wrong on, or a catalogued mistake). Of the {m.plausible} killed mutants a student could plausibly write "
            f"(autograder/authoring/mutants.py, PLAUSIBLE), the visible checks fail {m.plausible_seen} "
            f"({m.plausible_seen / max(m.plausible, 1):.0%}).", 100, break_on_hyphens=False))
        for mutant in m.surviving:  # each one a case the hidden tests miss, or an equivalent to list
            print(textwrap.fill(f"survives: {mutant.blank} {mutant.id}: {mutant.what}", 100, initial_indent="  ",
                                subsequent_indent="      ", break_on_hyphens=False))

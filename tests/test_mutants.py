"""Mutation testing of every lab's hidden tests (autograder/authoring/mutants.py): every mutant of every
reference blank fails the blank's hidden test, or is listed as equivalent in
``solutions/<module>/mutants.py`` with a reason; and every listed one is still made and still
passes (an entry that the test kills is no equivalent, and one that is no longer made is stale).

Every mutant is run (no sampling): about 1,000 in all, most in well under a second; the slowest
blanks (the particle filters' steps, whose checks are statistical) take up to 20 s each.
"""

from __future__ import annotations

import inspect

from autograder.authoring import mutants
from over_labs import over_labs


@over_labs
def test_every_mutant_fails_its_blanks_hidden_test_or_is_listed_as_equivalent(lab):
    report = mutants.report(lab, visible=False)
    print(f"\n{lab.id}: {report.mutants} mutants, {report.killed} killed, {report.equivalent} equivalent, "
          f"{len(report.surviving)} surviving, in {report.seconds:.0f} s")
    assert not report.surviving, "mutants that pass the hidden tests:\n" + "\n".join(
        f"  {m.blank} {m.id}: {m.what}" for m in report.surviving)


@over_labs
def test_each_equivalent_mutant_is_still_made_and_still_passes(lab):
    reference = lab.reference()
    made = {(m.blank, m.id): m for blank in lab.blanks()
            for m in mutants.mutants(blank, inspect.getsource(getattr(reference, blank)))}
    for key, reason in mutants.equivalent(lab).items():
        assert reason.strip(), f"{key} has no reason"
        assert key in made, f"{key} is listed as equivalent but no longer made: remove it from the list"
        assert not mutants.killed(lab, made[key]), f"{key} is listed as equivalent, but the hidden test fails it"

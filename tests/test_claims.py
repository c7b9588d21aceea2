"""Every result a lab states is marked, and every marked result is recomputed and holds.

A marker ``<!-- claim: <lab>/<name> -->`` in a source notebook's Markdown or in README must have a
check registered in ``solutions/<module>/claims.py``, and every check must have a marker: a check
whose sentence was deleted, or a sentence whose check was never written, fails here.
"""

import pytest

from autograder.authoring import claims
from autograder.labs import ROOT, Lab, all_labs
from over_labs import about

LABS = {lab.id: lab for lab in all_labs()}
CHECKS = {cid: c for lab in LABS.values() for cid, c in claims.checks(lab).items()}
MARKERS = claims.all_markers()
pytestmark = about(*LABS.values())


def test_every_claims_module_belongs_to_a_lab():
    modules = {p.parent.name for p in (ROOT / "solutions").glob("*/claims.py")}
    assert modules <= {lab.module for lab in LABS.values()}, f"claims modules without a lab: {modules - {l.module for l in LABS.values()}}"


def test_every_marker_names_a_lab():
    unknown = {cid: places for cid, places in MARKERS.items() if cid.split("/")[0] not in LABS}
    assert not unknown, f"claim markers that name no lab: {unknown}"


def test_every_marker_has_a_check():
    missing = {cid: places for cid, places in MARKERS.items() if cid not in CHECKS}
    assert not missing, "claim markers without a check in solutions/<module>/claims.py: " + "; ".join(
        f"{cid} ({', '.join(places)})" for cid, places in sorted(missing.items())
    )


def test_every_check_has_a_marker():
    orphans = sorted(set(CHECKS) - set(MARKERS))
    assert not orphans, f"checks whose claim no text states any more (delete them or mark the sentence): {orphans}"


def test_every_lab_states_at_least_one_checked_claim():
    bare = [lab for lab in LABS if not any(c.lab == lab for c in CHECKS.values())]
    assert not bare, f"labs whose notebooks mark no claim: {bare}"


def test_every_check_says_what_it_verifies():
    silent = [cid for cid, c in CHECKS.items() if not c.summary]
    assert not silent, f"claim checks without a docstring: {silent}"


@pytest.mark.parametrize("lab, claim_id", [(Lab(CHECKS[cid].lab), cid) for cid in sorted(CHECKS)], ids=sorted(CHECKS))
def test_claim_holds(lab, claim_id):
    CHECKS[claim_id].check()


@about()
def test_the_marker_pattern_and_the_rate_helper():
    text = "The band narrows. <!-- claim: train-kf/band-narrows --> And <!--claim:reentry-pf/x-2-->."
    assert claims.markers_in(text) == ["train-kf/band-narrows", "reentry-pf/x-2"]
    assert claims.markers_in("<!-- claim: Train_KF/x -->") == []
    assert claims.rate_at_least([True] * 19 + [False], 0.95, "x") == 0.95
    with pytest.raises(AssertionError, match="held in 18 of 20"):
        claims.rate_at_least([True] * 18 + [False] * 2, 0.95, "x")
    with pytest.raises(ValueError):
        claims.claim("not an id")

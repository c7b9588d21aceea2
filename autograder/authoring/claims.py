"""Claims: the sentences in which a lab states a result of its own computation, and their checks.

A sentence in a notebook's Markdown (story, model answers, rubrics) or in README that states a
result (a number, an ordering, "the band narrows", "about 95% of the time") carries a marker right
after it::

    The position error barely moves as q grows. <!-- claim: train-kf/q-scaling-position-flat -->

and ``solutions/<module>/claims.py`` registers a check under the same id::

    @claim("train-kf/q-scaling-position-flat")
    def _() -> None:
        '''The position RMSE changes by less than 10% over the q sweep, on each of 50 hours.'''
        ...  # recompute from the reference, raise AssertionError with a message when it fails

A check recomputes its claim from the reference (``solutions``), over enough seeds to be honest
about its spread. Where the claim depends on the random draw, the sentence says so, and the check
tests a rate with a stated tolerance (``rate_at_least``), never one lucky seed.
``tests/test_claims.py`` pairs markers with checks and runs every check.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

import nbformat

from autograder.labs import ROOT, Lab, all_labs

MARKER = re.compile(r"<!--\s*claim:\s*([a-z0-9-]+)/([a-z0-9-]+)\s*-->")
"""``<!-- claim: <lab>/<name> -->``: lab ids and names are lower case, digits and hyphens."""


@dataclass(frozen=True)
class Claim:
    """A registered check of one claim."""

    id: str
    """``<lab>/<name>``, as in the marker."""
    check: Callable[[], None]
    """Recomputes the claim; raises AssertionError, saying what it found, when the claim fails."""

    @property
    def lab(self) -> str:
        return self.id.split("/", 1)[0]

    @property
    def summary(self) -> str:
        """The first line of the check's docstring: what it verifies, in a sentence."""
        return (self.check.__doc__ or "").strip().splitlines()[0] if self.check.__doc__ else ""


_REGISTRY: dict[str, Claim] = {}


def claim(claim_id: str) -> Callable[[Callable[[], None]], Callable[[], None]]:
    """Register the decorated function as the check of the claim ``claim_id`` (``<lab>/<name>``)."""
    if not MARKER.fullmatch(f"<!-- claim: {claim_id} -->"):
        raise ValueError(f"A claim id is '<lab>/<name>' in lower case, digits and hyphens; got {claim_id!r}.")

    def register(check: Callable[[], None]) -> Callable[[], None]:
        if claim_id in _REGISTRY and _REGISTRY[claim_id].check.__qualname__ != check.__qualname__:
            raise ValueError(f"The claim {claim_id} has two checks.")
        _REGISTRY[claim_id] = Claim(claim_id, check)
        return check

    return register


def checks(lab: Lab) -> dict[str, Claim]:
    """The registered checks of a lab's claims (``solutions.<module>.claims``; none if it has no such module)."""
    try:
        lab.hidden_module("claims")
    except ModuleNotFoundError as error:
        if error.name != f"solutions.{lab.module}.claims":
            raise
    return {cid: c for cid, c in sorted(_REGISTRY.items()) if c.lab == lab.id}


def markers_in(text: str) -> list[str]:
    """The claim ids marked in a piece of text, in order."""
    return [f"{lab}/{name}" for lab, name in MARKER.findall(text)]


def notebook_markers(path: Path) -> dict[str, list[str]]:
    """Claim id -> where it is marked (``<file> cell <n>``), over a notebook's Markdown cells."""
    found: dict[str, list[str]] = {}
    nb = nbformat.read(path, as_version=4)
    for index, cell in enumerate(nb.cells):
        if cell.cell_type == "markdown":
            for cid in markers_in(cell.source):
                found.setdefault(cid, []).append(f"{path.relative_to(ROOT)} cell {index}")
    return found


def readme_markers() -> dict[str, list[str]]:
    """Claim id -> where it is marked in README.md."""
    found: dict[str, list[str]] = {}
    for number, line in enumerate((ROOT / "README.md").read_text().splitlines(), start=1):
        for cid in markers_in(line):
            found.setdefault(cid, []).append(f"README.md line {number}")
    return found


def all_markers() -> dict[str, list[str]]:
    """Claim id -> places, over every source notebook and README."""
    found = readme_markers()
    for lab in all_labs():
        for cid, places in notebook_markers(lab.source_notebook).items():
            found.setdefault(cid, []).extend(places)
    return found


def rate_at_least(outcomes: Iterable[bool], minimum: float, what: str) -> float:
    """Assert that at least the fraction ``minimum`` of ``outcomes`` hold; return the fraction.

    ``what`` names one outcome, for the message ("the truth inside the 2-sigma band").
    """
    values = [bool(o) for o in outcomes]
    if not values:
        raise ValueError("rate_at_least needs at least one outcome")
    fraction = sum(values) / len(values)
    assert fraction >= minimum, (
        f"{what}: held in {sum(values)} of {len(values)} trials ({fraction:.1%}); the claim needs at least {minimum:.1%}."
    )
    return fraction

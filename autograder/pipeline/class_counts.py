"""What a class's graded submissions of one lab add up to: ``LabCounts``, with a ``BlankCounts`` per test cell.

autograder/pipeline/class_report.py counts them; report_page.py and report_figure.py show them.
"""

from __future__ import annotations

from dataclasses import dataclass

from autograder.catalogues.mistakes import Mistake


@dataclass(frozen=True)
class BlankCounts:
    """The students of each outcome of one test cell (``test_<blank>``)."""

    cell: str
    full: tuple[str, ...]
    mistakes: dict[str, tuple[str, ...]]
    """Mistake slug -> students, most common first."""
    other: dict[str, tuple[str, ...]]
    """The kind of case alone wrong (WRONG_ONLY), or else the failing error's name -> students, most common first."""
    not_written: tuple[str, ...]
    visible_failed: tuple[str, ...]
    """The students who wrote the blank and handed it in with its visible checks failing (whatever its score)."""

    @property
    def blank(self) -> str:
        return self.cell.removeprefix("test_")

    @property
    def other_students(self) -> tuple[str, ...]:
        return tuple(sorted(s for students in self.other.values() for s in students))


@dataclass(frozen=True)
class LabCounts:
    """What one lab's graded submissions add up to."""

    lab: str
    scores: dict[str, float]
    """Student -> autograded score (points, before any late penalty)."""
    auto_max: float
    blanks: tuple[BlankCounts, ...]
    flagged: tuple[str, ...]
    late: tuple[str, ...]
    faulted: tuple[str, ...]
    visible_failed: tuple[str, ...]
    """The students with at least one written blank whose visible checks failed."""
    waiting: dict[str, tuple[str, ...]]
    """Written answer cell -> students whose hand grade is missing."""
    mistakes: dict[tuple[str, str], Mistake]
    """(blank, slug) -> the catalogued mistake."""

    @property
    def students(self) -> tuple[str, ...]:
        return tuple(sorted(self.scores))

    def score_bins(self) -> list[tuple[str, tuple[str, ...]]]:
        """The distribution of autograded scores: (score, its students), one bin per whole point from
        0 to the maximum (ten bins of equal width past 20 points)."""
        top = self.auto_max
        if top <= 20:
            labels, index = [f"{k}" for k in range(int(round(top)) + 1)], round
        else:
            width = top / 10
            labels = [f"{k * width:g} to {(k + 1) * width:g}" for k in range(10)]
            index = lambda score: min(int(score // width), 9)  # noqa: E731
        bins: list[list[str]] = [[] for _ in labels]
        for student, score in sorted(self.scores.items()):
            bins[index(score)].append(student)
        return [(label, tuple(students)) for label, students in zip(labels, bins)]

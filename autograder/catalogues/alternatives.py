"""The bank of correct alternatives, one module per lab (``solutions/<module>/alternatives.py``).

Where the mistakes catalogue proves that wrong answers lose their blank's points, this bank proves
the other half: answers that differ from the reference the way students' answers do (another
algebraic form, another factorisation, a loop for a vectorised expression, another sign
convention, another label's spelling, another resampling scheme the text accepts) keep full marks,
in the visible checks and in the hidden test, on every submission seed (tests/test_alternatives.py),
and through ``grade`` (the round trip).
"""

from __future__ import annotations

from dataclasses import dataclass

from autograder.labs import Lab


@dataclass(frozen=True)
class Alternative:
    """A correct answer to the blank ``blank`` that differs from the model answer."""

    blank: str
    slug: str
    """A short name, used in the student id of a submission that holds it."""
    why: str
    """How it differs from the model answer, in a sentence."""
    code: str
    """The whole answer cell: it defines the function ``blank`` (and may import what it needs)."""

    def student_id(self, lab: Lab) -> str:
        return f"{lab.id}_{self.blank}_alt-{self.slug}"


def catalogue(lab: Lab) -> tuple[Alternative, ...]:
    """The correct alternatives of a lab (``solutions.<module>.alternatives.ALTERNATIVES``)."""
    return lab.hidden_module("alternatives").ALTERNATIVES

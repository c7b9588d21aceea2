"""The catalogue of plausible student mistakes, one module per lab (``mistakes/train_kf.py``).

A mistake is an edit of one blank's model answer: the reference code with ``find`` replaced by
``replace``. The round-trip test grades a submission with each mistake and requires that it loses
that blank's points and no other blank's. tests/test_hidden_tests.py requires that the blank's
hidden test fails it the way ``raises`` says: by default with the hidden test's own AssertionError
(a wrong answer); a mistake that makes the student's function crash names the exception it raises.
When a student's function behaves like a mistake on every hidden case, the hidden test's message
gives the mistake's ``hint`` (autograder/hidden_tests/diagnosis.py).
"""

from __future__ import annotations

from dataclasses import dataclass

from autograder.labs import Lab


@dataclass(frozen=True)
class Mistake:
    """A plausible mistake in the blank ``blank`` (the name of the function it defines)."""

    blank: str
    slug: str
    """A short name, used in the demo student's id."""
    why: str
    """What the student got wrong, in a sentence."""
    find: str
    """Text in the model answer; it must occur there exactly once."""
    replace: str
    raises: type[Exception] = AssertionError
    """How the hidden test fails it: AssertionError, the hidden test's verdict on a wrong answer
    (the default); CallRuleBroken, the grader's verdict on a call that broke a rule every lab states
    (autograder/hidden_tests/isolate.py); another exception: the student's function itself raises it (a crash)."""
    hint: str = ""
    """What the student reads in the failing hidden test's message when their function behaves like
    this mistake on every hidden case (autograder/hidden_tests/diagnosis.py): whole sentences to the student,
    describing the mistake in words, with no number the reference computes."""

    def student_id(self, lab: Lab) -> str:
        return f"{lab.id}_{self.blank}_{self.slug}"

    def apply(self, answer: str) -> str:
        """The model answer ``answer`` with this mistake made in it."""
        count = answer.count(self.find)
        if count != 1:
            raise ValueError(
                f"Mistake {self.slug!r}: {self.find!r} occurs {count} times in the answer to "
                f"{self.blank}, and must occur exactly once. Update the catalogue."
            )
        return answer.replace(self.find, self.replace)


def catalogue(lab: Lab) -> tuple[Mistake, ...]:
    """The catalogued mistakes of a lab (``autograder.catalogues.mistakes.<module>.MISTAKES``)."""
    return lab.hidden_module("mistakes").MISTAKES

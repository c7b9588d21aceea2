"""How many calls each hidden test makes into the student's kernel, per lab and blank.

    .venv/bin/python benchmarks/kernel_calls_per_test.py

Runs every blank's hidden test in this process on the reference (the default submission seed) and
counts, for each: the calls of the student's function (each a round trip grader -> kernel -> grader
in grading), and the calls of served blanks that the reference's own version makes in those calls
(each a round trip kernel -> grader -> kernel, answered with the reference; any other call of a
served blank stays in the kernel: autograder/pipeline/served_calls.py). A failing test makes no
more calls: the diagnosis replays only the calls already made (autograder/hidden_tests/diagnosis.py).
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from autograder import cells  # noqa: E402
from autograder.hidden_tests import isolate  # noqa: E402
from autograder.labs import all_labs  # noqa: E402


def count_calls(lab, blank: str) -> tuple[int, int]:
    """(calls of the blank's function, calls of served blanks within them) in its hidden test."""
    reference, hidden = lab.reference(), lab.hidden_module("hidden_tests")
    served = isolate.called_blanks(reference, blank, hidden.BLANKS)
    counts = {"student": 0, "served": 0}
    saved = {name: getattr(reference, name) for name in served}

    def counting(function):
        def call(*args, **kwargs):
            counts["served"] += 1
            return function(*args, **kwargs)
        return call

    def observe(function, args, kwargs):
        counts["student"] += 1
        return function(*args, **kwargs)

    try:
        for name in served:
            setattr(reference, name, counting(saved[name]))
        with isolate.observed(observe):
            getattr(hidden, f"check_{blank}").__wrapped__(getattr(reference, blank))
    finally:
        for name, function in saved.items():
            setattr(reference, name, function)
    return counts["student"], counts["served"]


def main() -> None:
    print(f"{'lab':<18} {'blank':<28} {'calls':>6} {'served':>7}")
    for lab in all_labs():
        for blank in cells.blank_names(cells.read(lab.source_notebook)):
            student, served = count_calls(lab, blank)
            print(f"{lab.id:<18} {blank:<28} {student:>6} {served:>7}")


if __name__ == "__main__":
    main()

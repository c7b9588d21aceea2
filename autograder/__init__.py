"""The instructor's pipeline, thin over nbgrader: ``python -m autograder --help``.

Not installed and never shipped to students. Run it from the course root.
"""


def default_jobs() -> int:
    """How many submissions to grade at a time unless told: one per core of the machine."""
    import os

    return os.cpu_count() or 1

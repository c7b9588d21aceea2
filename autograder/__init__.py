"""The instructor's pipeline, thin over nbgrader: ``python -m autograder --help``.

Not installed and never shipped to students. Run it from the course root.
"""

"""The hidden side of every lab: one package per lab, ``solutions/<module>/``, holding what is
always edited together:

- ``reference.py``: the reference for every blank (the model answers' code), the lab's data build
  (``write_data``) and anything else that needs a blank's code (simulators);
- ``hidden_tests.py``: ``check_<blank>(func)`` for every blank, run by the grader;
- ``mistakes.py``: ``MISTAKES``, the catalogue of plausible student mistakes;
- ``claims.py``: the checks of the results that the lab's text states.

Beside them: ``shipped_npz.py`` (reproducible ``.npz`` files for the data builds) and ``records/``
(what the builds record so that tests can prove the shipped data in part).

For instructors and the grader's process only: never installed, never shipped to students, and
closed to grading kernels.
"""

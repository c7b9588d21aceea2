"""Shared test set-up (at the root, so that `pytest source/<lab>` alone gets it too).

The solved notebooks (nbval) and the grading kernels run hidden tests that import `solutions` and
`autograder`, which are not installed. Kernels inherit PYTHONPATH, so put the course root on it,
as nbgrader_config.py does for grading.
"""

import os

from autograder.labs import ROOT

os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH")) if p)

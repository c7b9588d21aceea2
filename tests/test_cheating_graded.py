"""Every cheat of train-kf graded through nbgrader alongside the solved notebook (the tests are in
tests/cheating_graded.py; the other labs' cheats are graded in tests/test_cheating_graded_other_labs.py)."""

from autograder.catalogues import cheats
from autograder.labs import get_lab
from cheating_graded import *  # noqa: F401,F403 (the tests, the graded fixture, the parametrization)
from over_labs import about

TRAIN = get_lab("train-kf")
CASES = [(TRAIN, cheat) for cheat in cheats.catalogue(TRAIN)]
HONEST = [TRAIN]
pytestmark = about(TRAIN)

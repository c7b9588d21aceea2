"""The cheats of every lab but train-kf, graded through nbgrader alongside each lab's solved notebook
(the tests are in tests/cheating_graded.py; train-kf's are all graded in tests/test_cheating_graded.py).

Graded here, for each lab: every cheat that the static scan does not catch (the runtime monitor, the
sanitize step or the hidden tests must stop it while the notebook is graded), and one cheat that the
scan catches, which shows the flag and its charge end to end in that lab; the labs take the kinds of
charge (one blank, every blank, none) in turn, so that each kind is shown outside train-kf too (train-kf
grades every one of its cheats, each kind several times). The scan's other catches go through the same lab-independent flagging
(autograder/integrity/flag.py): tests/test_integrity.py scans every cheat of every lab, and
benchmarks/grading_throughput.py grades every cheat of every lab. Grading all of them here (27 per
lab) would add about ten minutes of grading to every CI run.
"""

from autograder.catalogues import cheats
from autograder.labs import get_lab
from cheating_graded import *  # noqa: F401,F403 (the tests, the graded fixture, the parametrization)
from over_labs import LABS, about

HONEST = [lab for lab in LABS if lab != get_lab("train-kf")]
pytestmark = about(*HONEST)


CHARGES = ("blank", "all", "none")
"""What a cheat games, so what its flag costs: one blank, every blank, or none."""


def _cases(lab, games: str):
    catalogue = cheats.catalogue(lab)
    picked = [c for c in catalogue if cheats.STATIC not in c.caught_by]
    picked += [next(c for c in catalogue if cheats.STATIC in c.caught_by and c.games == games)]
    return [(lab, cheat) for cheat in picked]


CASES = [case for k, lab in enumerate(HONEST) for case in _cases(lab, CHARGES[k % len(CHARGES)])]

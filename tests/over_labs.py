"""Parametrising a test over every lab, with the lab id as the test id (``pytest -k train-kf``)."""

import pytest

from autograder.labs import all_labs

LABS = all_labs()
over_labs = pytest.mark.parametrize("lab", LABS, ids=[lab.id for lab in LABS])

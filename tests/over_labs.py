"""Parametrising a test over every lab, with the lab id as the test id, and choosing labs with
``pytest --lab`` (conftest.py at the root): a fixture that grades labs grades only the ``chosen``
ones, and ``about`` marks a test that concerns labs without being parametrized by one."""

from collections.abc import Iterable

import pytest

from autograder.labs import Lab, all_labs

LABS = all_labs()
over_labs = pytest.mark.parametrize("lab", LABS, ids=[lab.id for lab in LABS])


def chosen(config: pytest.Config, labs: Iterable[Lab]) -> list[Lab]:
    """The labs of ``labs`` that ``pytest --lab`` chose (without --lab, all of them)."""
    wanted = config.getoption("lab")
    return [lab for lab in labs if not wanted or lab.id in wanted]


def about(*labs: Lab) -> pytest.MarkDecorator:
    """The mark of a test that concerns ``labs`` (a graded class of them, a check over all of them),
    which ``pytest --lab`` keeps when it names one of them; ``about()`` marks a test of the kit's own
    machinery in a file whose other tests concern labs."""
    return pytest.mark.labs(*(lab.id for lab in labs))

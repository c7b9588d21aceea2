"""Whether a random blank draws from the generator it is given, and only from it.

A statistical hidden test accepts any step whose draws have the right distribution, wherever they come
from. A step that draws from a generator of its own (``np.random.default_rng()``), or from NumPy's global
generator with its state put back (``np.random.set_state``), passed such a test (adversarial review of
issue 31), though the lab says to draw every random number from ``rng``. The check here says so by its
consequence, whatever the route: two generators in the same state must give the same result, and two in
different states different results.

What a check by consequence cannot see (two adversarial reviews of issue 30, which stated it as a limit): a step
that derives its own generator from the one it is given (from its state, or through a table kept from call to call)
and moves the given one, so that its results follow the given generator's state as honest draws do. Its draws are
right in distribution and reproducible from the seed, like those of a generator seeded with rng.integers(...), which
the lab allows; it wins back no more than this rule's own marks.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from autograder.hidden_tests import cases
from autograder.hidden_tests.isolate import CallRuleBroken


def _same(first: Any, second: Any) -> bool:
    """Whether two results are equal, bit for bit where they are arrays (NaN equal to NaN)."""
    if isinstance(first, (tuple, list)) and isinstance(second, (tuple, list)):
        return len(first) == len(second) and all(_same(a, b) for a, b in zip(first, second))
    if isinstance(first, dict) and isinstance(second, dict):
        return first.keys() == second.keys() and all(_same(first[k], second[k]) for k in first)
    try:
        a, b = np.asarray(first), np.asarray(second)
        return a.shape == b.shape and bool(np.array_equal(a, b, equal_nan=a.dtype.kind in "fc"))
    except (TypeError, ValueError):
        return first == second


def check_draws_from_rng(call: Callable[[np.random.Generator], Any], name: str, *stream: int) -> None:
    """Fail unless ``call(rng)``, a call of the blank ``name`` on one fixed case whose result depends on its draws,
    gives a new result when it is called again with the same generator (as a filter's next step is), the same
    result for a generator in the same state, and another for a generator in another state. Reviews of issue 30:
    a step that drew from a copy of rng (copy.deepcopy, a generator seeded from it) kept its marks, and an honest
    one that spawned from rng must keep them."""
    given = cases.rng(*stream, 0)
    first = call(given)
    if _same(first, call(given)):
        raise CallRuleBroken(
            f"{name} gave the same result when it was called twice with one generator, as a filter's next step "
            "would be: it does not draw from that generator as it goes (a copy of rng, a generator seeded from it "
            "or a fixed seed, np.random with its state put back, draws made once and kept for later calls), so every "
            "step would draw the same numbers. Draw every random number with rng itself.")
    if not _same(first, call(cases.rng(*stream, 0))):
        raise CallRuleBroken(
            f"{name} gave different results when it was given two generators in the same state: it draws from "
            "a generator of its own (np.random.default_rng() inside the function, or one kept from an earlier call), "
            "from np.random or from Python's random module. Draw every random number with the rng it is given, so "
            "that the same seed gives the same result.")
    if _same(first, call(cases.rng(*stream, 1))):
        raise CallRuleBroken(
            f"{name} gave the same result for generators in different states: its draws do not come from the "
            "rng it is given. Draw every random number with rng.")

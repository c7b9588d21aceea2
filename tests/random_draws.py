"""Tests that draw random numbers: each states its false-fail probability and runs on 21 seeds.

A test that draws random numbers can pass on its pinned seed by luck. So every such test in
``tests/``

- is decorated with ``@random_draws(false_fail=..., why=...)``: ``false_fail`` is the probability
  that it fails for correct code, derived from its statistic's distribution (0 for an exact
  identity, where the draw only picks the case), at most ``FALSE_FAIL_LIMIT``; ``why`` says where
  the number comes from, in a sentence;
- takes a ``seed`` argument, from which it derives every generator it uses
  (``np.random.default_rng([seed, ...])``); ``tests/conftest.py`` runs it on ``SEEDS``: seed 0
  and 20 other seeds, so a test that holds only on a lucky seed fails;
- or, when its body already loops over at least 21 seeds of its own, says so with ``own_seeds``
  (the number of seeds it loops over) and takes no ``seed`` argument;
- or, when it checks one seed's exact output (a reproducibility test, a regression pin, a rebuild of
  shipped data), says so with ``fixed_seed=True``: rerunning it on other seeds would test nothing.

``tests/test_random_draws.py`` enforces this on the source. ``python tests/random_draws.py``
prints every such test with its stated false-fail probability.
"""

from __future__ import annotations

import ast
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

FALSE_FAIL_LIMIT = 1e-6
"""Largest false-fail probability a test may state."""

SEEDS = tuple(range(21))
"""Seed 0, and 20 other seeds, for every test that takes ``seed``."""

TESTS = Path(__file__).resolve().parent


def random_draws(*, false_fail: float, why: str, own_seeds: int = 0, fixed_seed: bool = False,
                 scope: str = "function") -> pytest.MarkDecorator:
    """Mark a test that draws random numbers (see the module's docstring).

    ``scope`` is the scope of the ``seed`` parameter: "module" lets a module-scoped fixture take ``seed``.
    """
    return pytest.mark.random_draws(false_fail=false_fail, why=why, own_seeds=own_seeds,
                                    fixed_seed=fixed_seed, scope=scope)


@dataclass(frozen=True)
class Statement:
    """One decorated test, as its source states it."""

    file: str
    test: str
    false_fail: float
    why: str
    own_seeds: int
    fixed_seed: bool
    takes_seed: bool

    @property
    def seeds(self) -> str:
        """How the test covers more than one seed, in words."""
        if self.fixed_seed:
            return "one seed (exact output)"
        if self.own_seeds:
            return f"{self.own_seeds} seeds in its body"
        return f"{len(SEEDS)} seeds"


def decorator_keywords(function: ast.FunctionDef | ast.AsyncFunctionDef) -> dict | None:
    """The literal keyword arguments of the function's ``random_draws(...)`` decorator, or None."""
    for decorator in function.decorator_list:
        if isinstance(decorator, ast.Call) and getattr(decorator.func, "id", None) == "random_draws":
            return {k.arg: ast.literal_eval(k.value) for k in decorator.keywords}
    return None


def statements(files: list[Path] | None = None) -> list[Statement]:
    """Every ``@random_draws`` test in ``files`` (default: tests/test_*.py), read from the source."""
    found = []
    for path in files or sorted(TESTS.glob("test_*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                keywords = decorator_keywords(node)
                if keywords is not None:
                    found.append(Statement(
                        path.name, node.name, float(keywords["false_fail"]), keywords["why"],
                        int(keywords.get("own_seeds", 0)), bool(keywords.get("fixed_seed", False)),
                        "seed" in [a.arg for a in node.args.args]))
    return found


def main() -> int:
    """Print every test that draws random numbers, with its stated false-fail probability."""
    rows = statements()
    for row in rows:
        print(f"{row.file}::{row.test}\n    false-fail {row.false_fail:.1e} on each of {row.seeds}: {row.why}")
    print(f"{len(rows)} tests draw random numbers; the largest stated false-fail probability is "
          f"{max(r.false_fail for r in rows):.1e} (limit {FALSE_FAIL_LIMIT:.0e}).")
    return 0


if __name__ == "__main__":
    sys.exit(main())

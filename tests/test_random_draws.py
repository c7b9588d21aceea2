"""Every test that draws random numbers states its false-fail probability and runs on 21 seeds.

The rules are in tests/random_draws.py. These tests read the test files' source, so a new test that
draws random numbers without saying how often it fails wrongly cannot land.
"""

import ast
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from random_draws import FALSE_FAIL_LIMIT, SEEDS, TESTS, decorator_keywords, statements

FILES = sorted(TESTS.glob("test_*.py"))


def _functions(tree: ast.Module) -> dict[str, ast.FunctionDef]:
    return {n.name: n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef)}


def _is_generator_call(node: ast.AST) -> bool:
    return isinstance(node, ast.Call) and getattr(node.func, "attr", getattr(node.func, "id", None)) == "default_rng"


def _names(node: ast.AST) -> set[str]:
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}


def _draws(function: ast.FunctionDef, functions: dict[str, ast.FunctionDef], seen: frozenset = frozenset()) -> bool:
    """Whether the function creates a generator, itself or through a function or fixture of its module."""
    if any(_is_generator_call(n) for n in ast.walk(function)):
        return True
    called = {n.func.id for n in ast.walk(function) if isinstance(n, ast.Call) and isinstance(n.func, ast.Name)}
    requested = {a.arg for a in function.args.args}
    return any(_draws(functions[name], functions, seen | {function.name})
               for name in (called | requested) & functions.keys() - seen - {function.name})


@pytest.mark.parametrize("path", FILES, ids=[p.name for p in FILES])
def test_every_test_that_draws_random_numbers_is_marked_and_seeded(path):
    tree = ast.parse(path.read_text())
    functions = _functions(tree)
    problems = []
    for name, function in functions.items():
        marked = decorator_keywords(function)
        if name.startswith("test_") and marked is None and _draws(function, functions):
            problems.append(f"{name} draws random numbers but has no @random_draws(false_fail=..., why=...)")
        pinned = marked is not None and (marked.get("fixed_seed") or marked.get("own_seeds"))
        for node in ast.walk(function):
            # Every generator derives from the test's seed, so that the 20 other seeds reach it.
            if _is_generator_call(node) and not pinned and "seed" not in _names(node):
                problems.append(f"{name} line {node.lineno}: default_rng(...) does not derive from `seed`")
            # A literal seed handed to other code is a pinned draw too.
            if isinstance(node, ast.Call) and not pinned:
                for keyword in node.keywords:
                    if keyword.arg == "seed" and isinstance(keyword.value, ast.Constant):
                        problems.append(f"{name} line {node.lineno}: seed={keyword.value.value!r} is pinned")
    assert not problems, "\n".join(problems)


def test_every_statement_is_within_the_limit_and_covers_21_seeds():
    rows = statements()
    assert rows, "no test states a false-fail probability"
    problems = []
    for row in rows:
        where = f"{row.file}::{row.test}"
        if not 0.0 <= row.false_fail <= FALSE_FAIL_LIMIT:
            problems.append(f"{where}: false-fail {row.false_fail:g} is above {FALSE_FAIL_LIMIT:g}")
        if len(row.why.split()) < 6:
            problems.append(f"{where}: `why` must say where the false-fail probability comes from")
        ways = [row.takes_seed, row.own_seeds > 0, row.fixed_seed]
        if sum(ways) != 1:
            problems.append(f"{where}: takes `seed`, loops over own_seeds, or is fixed_seed: exactly one")
        if row.own_seeds and row.own_seeds < len(SEEDS):
            problems.append(f"{where}: loops over {row.own_seeds} seeds, fewer than {len(SEEDS)}")
    assert not problems, "\n".join(problems)


def _pytest(folder: Path) -> subprocess.CompletedProcess:
    """pytest on ``folder`` alone, in a fresh process, with only the hooks of tests/conftest.py."""
    return subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist",
                           "--rootdir", str(folder), str(folder)], capture_output=True, text=True, cwd=folder)


def test_a_seeded_test_runs_on_21_seeds_and_an_unmarked_one_is_refused(tmp_path):
    for name in ("conftest.py", "machine_needs.py", "random_draws.py", "time_per_file.py"):
        shutil.copy(TESTS / name, tmp_path / name)
    (tmp_path / "test_demo.py").write_text(
        "import numpy as np\nfrom random_draws import random_draws\n\n"
        "@random_draws(false_fail=0.0, why='an identity: the draw only picks the case')\n"
        "def test_marked(seed):\n    assert np.random.default_rng(seed).random() < 1\n")
    run = _pytest(tmp_path)
    assert f"{len(SEEDS)} passed" in run.stdout, run.stdout + run.stderr
    (tmp_path / "test_demo.py").write_text("def test_unmarked(seed):\n    pass\n")
    run = _pytest(tmp_path)
    assert run.returncode != 0 and "states no false-fail" in run.stdout + run.stderr, run.stdout + run.stderr


def test_the_listing_prints_every_statement():
    run = subprocess.run([sys.executable, str(TESTS / "random_draws.py")], capture_output=True, text=True, check=True)
    for row in statements():
        assert f"{row.file}::{row.test}" in run.stdout
    assert f"{len(statements())} tests draw random numbers" in run.stdout

"""Mutation testing of the hidden tests: wrong versions of every reference blank, made
automatically, that the blank's hidden test must fail.

A mistake catalogue proves that the wrong answers someone thought of lose their points; mutants
prove it for the small slips nobody listed. Each mutant is the reference's source of one blank with
one change, of the usual kinds: an arithmetic operator swapped (``+``/``-``, ``*``/``/``, ``@`` for
``*``), a comparison turned (``<``/``<=``, ``==``/``!=``), a unary minus dropped or added, a
constant changed (``n`` to ``n + 1``, ``0``/``1``, a float scaled), an index moved by one, a
transpose dropped (``.T``), the first two arguments of a call swapped (unless they commute, as in
``np.hypot`` or ``swapaxes``), a term of a sum dropped, a
``True`` turned ``False``, an index or a ``range`` off by one, a statement dropped, a returned value
negated. It is compiled in the reference module's namespace, as a catalogued
mistake is, and the blank's hidden test runs on it, in this process, on the default seed, with a
time limit: a mutant is killed if the test fails it (an error of the test, or a crash or a hang of
the mutant). A mutant that the test passes survives, unless it is listed as equivalent in
``solutions/<module>/mutants.py`` (``EQUIVALENT``: mutant id -> a one-line reason a reviewer can
check: it computes the same thing, or it changes what no correct answer depends on).

Why the standard library's ``ast`` and not a mutation-testing library: mutmut 3 and cosmic-ray both
mutate whole modules on disk and run a test command (pytest) per mutant, with a session database
(cosmic-ray) or trampolines installed at import (mutmut); neither applies its operators to the
source of one function and hands back the mutated function, which is what a hidden test needs. The
operators above are theirs.
"""

from __future__ import annotations

import ast
import contextlib
import copy
import inspect
import signal
import textwrap
import time
import types
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np

from autograder.authoring.visible_checks import visible_verdicts
from autograder.labs import Lab

PLAUSIBLE = frozenset({"operator", "comparison", "sign", "transpose", "swap-arguments", "drop-term", "index", "off-by-one"})
"""The kinds of mutant a student could plausibly write (a wrong sign or operator, a missing transpose or
term, swapped arguments, an index or a range off by one); changed constants, dropped statements and
negated returns are the mutation tool's, not a student's. The report says how many of these the
visible checks already fail (issue: visible checks that can see the common mistakes)."""

TIME_LIMIT_S = 20
"""A mutant whose hidden test runs longer than this is killed (it hangs, or it is far too slow)."""

SWAPS: dict[type, type] = {ast.Add: ast.Sub, ast.Sub: ast.Add, ast.Mult: ast.Div, ast.Div: ast.Mult,
                           ast.MatMult: ast.Mult, ast.Pow: ast.Mult, ast.FloorDiv: ast.Div, ast.Mod: ast.FloorDiv}
COMPARISONS: dict[type, type] = {ast.Lt: ast.LtE, ast.LtE: ast.Lt, ast.Gt: ast.GtE, ast.GtE: ast.Gt,
                                 ast.Eq: ast.NotEq, ast.NotEq: ast.Eq, ast.Is: ast.IsNot, ast.IsNot: ast.Is}


SYMMETRIC = frozenset({"hypot", "minimum", "maximum", "fmin", "fmax", "min", "max", "swapaxes", "add", "multiply",
                       "logaddexp", "allclose", "isclose", "array_equal"})
"""Functions whose first two arguments commute: swapping them makes no mutant."""


def _called_name(call: ast.Call) -> str:
    """The last name of a call's function (``np.hypot`` -> ``hypot``, ``x.swapaxes`` -> ``swapaxes``)."""
    func = call.func
    return func.attr if isinstance(func, ast.Attribute) else func.id if isinstance(func, ast.Name) else ""


@dataclass(frozen=True)
class Mutant:
    """One change to a blank's reference source."""

    blank: str
    id: str
    """``<operator>@<line>:<column>[/<variant>]``, the line counted from the function's ``def``."""
    what: str
    """The change, in words: the original and the mutated text."""
    source: str


def _variants(node: ast.AST) -> Iterator[tuple[str, ast.AST | None, str]]:
    """(operator, replacement node or None to drop the node from its sum, variant) for ``node``."""
    if isinstance(node, ast.BinOp) and type(node.op) in SWAPS:
        yield "operator", ast.BinOp(node.left, SWAPS[type(node.op)](), node.right), ""
        if isinstance(node.op, (ast.Add, ast.Sub)):
            yield "drop-term", node.left, "right"
            if isinstance(node.op, ast.Add):
                yield "drop-term", node.right, "left"
    elif isinstance(node, ast.Compare) and len(node.ops) == 1 and type(node.ops[0]) in COMPARISONS:
        yield "comparison", ast.Compare(node.left, [COMPARISONS[type(node.ops[0])]()], node.comparators), ""
    elif isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        yield "sign", node.operand, "drop"
    elif isinstance(node, ast.Constant) and isinstance(node.value, bool):
        yield "constant", ast.Constant(not node.value), ""
    elif isinstance(node, ast.Constant) and isinstance(node.value, int):
        yield "constant", ast.Constant(node.value + 1), "plus-one"
        if node.value != 0:
            yield "constant", ast.Constant(0), "zero"
    elif isinstance(node, ast.Constant) and isinstance(node.value, float):
        yield "constant", ast.Constant(node.value * 1.5 if node.value else 1.0), "scaled"
    elif isinstance(node, ast.Attribute) and node.attr == "T":
        yield "transpose", node.value, ""
    elif (isinstance(node, ast.Call) and len(node.args) >= 2 and not any(isinstance(a, ast.Starred) for a in node.args[:2])
          and _called_name(node) not in SYMMETRIC):
        yield "swap-arguments", ast.Call(node.func, [node.args[1], node.args[0], *node.args[2:]], node.keywords), ""
    elif isinstance(node, ast.Return) and node.value is not None and not isinstance(node.value, ast.Tuple):
        yield "negate-return", ast.Return(ast.UnaryOp(ast.USub(), node.value)), ""
    if isinstance(node, ast.Subscript) and isinstance(node.slice, (ast.Name, ast.Constant)) and not (
            isinstance(node.slice, ast.Constant) and not isinstance(node.slice.value, int)):
        for variant, op in (("plus-one", ast.Add()), ("minus-one", ast.Sub())):
            yield "index", ast.Subscript(node.value, ast.BinOp(node.slice, op, ast.Constant(1)), node.ctx), variant
    if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "range"
            and len(node.args) == 1):
        yield "off-by-one", ast.Call(node.func, [ast.BinOp(node.args[0], ast.Sub(), ast.Constant(1))], []), ""
    if isinstance(node, (ast.Assign, ast.AugAssign, ast.Expr)) and not (
            isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant)):
        yield "drop-statement", ast.Pass(), ""


class _Replace(ast.NodeTransformer):
    """Replaces the one node at ``target`` (its position in ``ast.walk`` order) with ``replacement``."""

    def __init__(self, target: int, replacement: ast.AST):
        self.target, self.replacement, self.index = target, replacement, -1

    def visit(self, node):
        self.index += 1
        if self.index == self.target:
            return self.replacement
        return self.generic_visit(node)


def _positions(tree: ast.AST) -> list[ast.AST]:
    """Every node, in the order ``_Replace`` counts them (pre-order)."""
    nodes = []

    def walk(node):
        nodes.append(node)
        for child in ast.iter_child_nodes(node):
            walk(child)

    walk(tree)
    return nodes


def mutants(blank: str, source: str) -> list[Mutant]:
    """Every mutant of the function ``blank`` whose source is ``source`` (docstrings left alone)."""
    source = textwrap.dedent(source)
    tree = ast.parse(source)
    [function] = tree.body
    docstring = function.body[0] if (function.body and isinstance(function.body[0], ast.Expr)
                                     and isinstance(function.body[0].value, ast.Constant)) else None
    skip = {id(n) for n in ast.walk(docstring)} if docstring is not None else set()
    skip |= {id(n) for n in ast.walk(function.args)} | {id(function)}
    found: list[Mutant] = []
    for index, node in enumerate(_positions(tree)):
        if id(node) in skip:
            continue
        for operator, replacement, variant in _variants(node):
            mutated = _Replace(index, copy.deepcopy(replacement)).visit(copy.deepcopy(tree))
            try:
                text = ast.unparse(ast.fix_missing_locations(mutated))
            except (ValueError, TypeError):
                continue
            line = getattr(node, "lineno", 0) - function.lineno
            mutant_id = f"{operator}@{line}:{getattr(node, 'col_offset', 0)}" + (f"/{variant}" if variant else "")
            original = ast.get_source_segment(source, node) or ast.unparse(node)
            found.append(Mutant(blank, mutant_id, f"{original.splitlines()[0][:60]} -> "
                                f"{ast.unparse(replacement).splitlines()[0][:60] if replacement is not None else ''}",
                                text))
    unique = {m.source: m for m in found if m.source != ast.unparse(tree)}
    return list(unique.values())


def equivalent(lab: Lab) -> dict[tuple[str, str], str]:
    """(blank, mutant id) -> why it is equivalent, from ``solutions/<module>/mutants.py``."""
    try:
        return dict(lab.hidden_module("mutants").EQUIVALENT)
    except ModuleNotFoundError:
        return {}


class _TimeLimit(Exception):
    """The mutant's hidden test ran past TIME_LIMIT_S."""


@contextlib.contextmanager
def _time_limit(seconds: float):
    def stop(signum, frame):
        raise _TimeLimit

    previous = signal.signal(signal.SIGALRM, stop)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def killed(lab: Lab, mutant: Mutant) -> bool:
    """Whether the blank's hidden test fails ``mutant`` (in this process, on the default seed)."""
    return failure(lab, mutant) is not None


def failure(lab: Lab, mutant: Mutant) -> BaseException | None:
    """What the blank's hidden test raises on ``mutant`` (None: it passes it), with the message a
    student would read (labelled cases and the diagnosis included)."""
    reference = lab.reference()
    namespace = dict(vars(reference))
    try:
        exec(compile(mutant.source, inspect.getsourcefile(reference) or "<mutant>", "exec"), namespace)
        function: Callable = namespace[mutant.blank]
    except Exception as error:  # noqa: BLE001 (a mutant that does not even compile is no answer)
        return error
    check = getattr(lab.hidden_module("hidden_tests"), f"check_{mutant.blank}")
    try:
        with _time_limit(TIME_LIMIT_S), np.errstate(all="ignore"):
            check(function)
    except BaseException as error:  # noqa: BLE001 (any failure kills it; KeyboardInterrupt is the user's)
        if isinstance(error, KeyboardInterrupt):
            raise
        return error
    return None


@dataclass(frozen=True)
class Report:
    """A lab's mutation report."""

    lab: str
    mutants: int
    killed: int
    equivalent: int
    surviving: tuple[Mutant, ...]
    seconds: float
    narrowed: int
    """Killed mutants whose failing message says on which kinds of case the function is right and on
    which wrong (autograder/hidden_tests/case_kinds.py), or names a catalogued mistake."""
    plausible: int
    """Killed mutants of the PLAUSIBLE kinds."""
    plausible_seen: int
    """Of those, the ones that the blank's visible checks already fail, in the solved notebook."""


def report(lab: Lab, blanks: list[str] | None = None, *, visible: bool = True) -> Report:
    """Make and run every mutant of the lab's blanks (all of them by default); with ``visible``, run the
    visible checks on the plausible killed ones too (else ``plausible_seen`` is 0)."""
    from autograder import cells

    start = time.monotonic()
    reference = lab.reference()
    listed = equivalent(lab)
    total = dead = same = narrowed = 0
    surviving, plausible = [], []
    for blank in blanks or cells.blank_names(cells.read(lab.source_notebook)):
        for mutant in mutants(blank, inspect.getsource(getattr(reference, blank))):
            total += 1
            if (blank, mutant.id) in listed:
                same += 1
                continue
            error = failure(lab, mutant)
            if error is None:
                surviving.append(mutant)
                continue
            dead += 1
            message = " ".join([str(error), *getattr(error, "__notes__", [])])
            narrowed += f"Your {blank} is right on " in message or "Diagnosis:" in message
            if mutant.id.split("@")[0] in PLAUSIBLE:
                plausible.append(mutant)
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        # a mutant's NaNs and divisions by zero are what it is: its verdict is measured, its warnings would
        # only fill the instructor's terminal (`python -m autograder labs`)
        warnings.simplefilter("ignore", RuntimeWarning)
        verdicts = visible_verdicts(lab, [(f"{m.blank} {m.id}", m.blank, m.source) for m in plausible if visible])
    seen = sum(verdicts.get(f"{m.blank} {m.id}") is not None for m in plausible)
    return Report(lab.id, total, dead, same, tuple(surviving), time.monotonic() - start, narrowed, len(plausible), seen)

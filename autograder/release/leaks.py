"""Checks that what students get holds no solution, no hidden test and no way to the reference.

A leak is any of: an nbgrader solution or hidden-test delimiter; an import of, or a path to, the
``solutions`` package (or the hidden tests); or the body of a function defined in ``solutions/``.
Bodies are compared as normalised syntax trees (docstrings dropped, names and layout as written),
so a renamed copy of a reference function is caught, while the release's stubs, which rightly
share the reference's names, are not. ``course/`` is checked too: it must not implement a blank.
"""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass
from pathlib import Path

import nbformat

from autograder import cells
from autograder.labs import ROOT, all_labs

TEXT_PATTERNS = {
    "a solution delimiter": re.compile(r"(BEGIN|END) SOLUTION"),
    "a hidden-test delimiter": re.compile(r"(BEGIN|END) HIDDEN TESTS"),
    "a mark-scheme delimiter": re.compile(r"(BEGIN|END) MARK SCHEME"),
    "an import of the reference": re.compile(r"(^|[^\w.])(import|from)\s+(solutions|autograder)\b", re.M),
    "a reference to the hidden packages": re.compile(
        r"\b(solutions|autograder)(/|\\|\.[A-Za-z_])|__import__\(\s*['\"](solutions|autograder)|"
        r"['\"](solutions|autograder)['\"]"
    ),
}
TEXT_SUFFIXES = {".py", ".ipynb", ".md", ".txt", ".toml", ".cfg", ".json", ".csv", ".ini", ".yml", ".yaml"}
MIN_BODY_NODES = 8
"""Bodies smaller than this many syntax nodes (``return x``) are too generic to call a leak."""


@dataclass(frozen=True)
class Leak:
    path: Path
    what: str

    def __str__(self) -> str:
        return f"{self.path}: {self.what}"


def _body_key(func: ast.FunctionDef) -> str | None:
    body = func.body
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) and isinstance(body[0].value.value, str):
        body = body[1:]
    if sum(1 for stmt in body for _ in ast.walk(stmt)) < MIN_BODY_NODES:
        return None
    return ast.dump(ast.Module(body=body, type_ignores=[]), annotate_fields=False)


def _functions(code: str) -> list[ast.FunctionDef]:
    try:
        return [node for node in ast.walk(ast.parse(code)) if isinstance(node, ast.FunctionDef)]
    except SyntaxError:
        return cells.defined_functions(code) if "%" in code else []


def reference_bodies() -> dict[str, str]:
    """Normalised function body -> qualified name, for every function in ``solutions/``."""
    bodies = {}
    # a lab's draft is its notebook as text: its answer cells are the reference's functions (build refuses a
    # model answer unlike them), and every other cell is what students get, so a helper that a visible check
    # defines in the draft is no leak (it was reported as one in the release: issue 33's rewrite of reentry-pf)
    for path in sorted(p for p in (ROOT / "solutions").rglob("*.py") if p.name != "draft.py"):
        for func in _functions(path.read_text()):
            key = _body_key(func)
            if key is not None:
                bodies[key] = f"solutions/{path.relative_to(ROOT / 'solutions')}:{func.name}"
    return bodies


def _code_of(path: Path) -> str:
    if path.suffix == ".ipynb":
        nb = nbformat.read(path, as_version=4)
        return "\n\n".join(
            "\n".join(line for line in c.source.splitlines() if not line.lstrip().startswith(("%", "!")))
            for c in nb.cells
            if c.cell_type == "code"
        )
    return path.read_text()


def find_leaks(tree: Path) -> list[Leak]:
    """Every leak in the files under ``tree`` (a release folder or a student bundle)."""
    bodies = reference_bodies()
    leaks = []
    for path in sorted(p for p in tree.rglob("*") if p.is_file()):
        rel = path.relative_to(tree)
        if any(part in ("solutions", "autograder") for part in rel.parts[:-1]) or path.stem in ("solutions", "autograder"):
            leaks.append(Leak(rel, "a file of the hidden packages"))
            continue
        if path.suffix not in TEXT_SUFFIXES:
            continue
        text = path.read_text(errors="replace")
        leaks += [Leak(rel, what) for what, pattern in TEXT_PATTERNS.items() if pattern.search(text)]
        if path.suffix in (".py", ".ipynb"):
            for func in _functions(_code_of(path)):
                key = _body_key(func)
                if key in bodies:
                    leaks.append(Leak(rel, f"function {func.name} has the body of {bodies[key]}"))
    return leaks


def blanks_in_course() -> list[Leak]:
    """Functions in ``course/`` that implement a blank: same name as a blank, or a reference body."""
    blanks = {name for lab in all_labs() for name in cells.blank_names(cells.read(lab.source_notebook))}
    bodies = reference_bodies()
    found = []
    for path in sorted((ROOT / "course").rglob("*.py")):
        for func in _functions(path.read_text()):
            if func.name in blanks:
                found.append(Leak(path.relative_to(ROOT), f"defines {func.name}, which is a blank"))
            elif _body_key(func) in bodies:
                found.append(Leak(path.relative_to(ROOT), f"{func.name} has the body of {bodies[_body_key(func)]}"))
    return found

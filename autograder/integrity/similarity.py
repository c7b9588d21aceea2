"""Similarity of students' answers, for a human to review: likely copying, per lab and per blank.

Answers are compared after normalisation, not as raw text. A code answer is parsed, its comments,
docstrings, imports and formatting are dropped (``ast.unparse``), the function's arguments are
renamed ``a0``, ``a1``, ... by position and every other name the answer binds (variables, loop
variables, helper functions) becomes ``_``; names it does not bind (``np``, the blank's own name,
other blanks it calls, attributes, keyword arguments) stay as they are. So renaming variables,
reformatting, rewriting comments and moving a statement do not hide a copy. A written answer is
compared as its lower-case words and symbols. The score of a pair is difflib's ratio of their
token sequences (1: identical after normalisation).

The report only lists pairs for review. It reads notebooks and never changes a grade.
"""

from __future__ import annotations

import ast
import difflib
import io
import re
import tokenize
from dataclasses import dataclass
from itertools import combinations
from pathlib import Path

from autograder import cells, csv_cells
from autograder.labs import Lab, all_labs
from autograder.pipeline.intake import MAX_SUBMISSION_BYTES

THRESHOLD = 0.8
"""Pairs scoring at least this are listed."""
MAX_COMPARED_TOKENS = 5_000
"""The most tokens of an answer the report parses and compares, comments and line breaks aside (a lab's
longest model answer has about 1,500): parsing costs hundreds of bytes per token and comparing up to
the product of two answers' lengths, so a longer one is listed as not compared. Comments do not
count, so that a copy padded with them is still compared (an adversarial review found that a cap on
characters let it through)."""
MAX_READ_CHARS = 1_000_000
"""The most characters of an answer the report reads at all (to count its tokens)."""
TEXT_STUB = "YOUR ANSWER HERE"


class _Canonical(ast.NodeTransformer):
    """Renames the names in ``bound``: a function's arguments to ``a0``, ``a1``, ... by position,
    every other name to ``_``, so that neither new names nor the order in which statements
    introduce them matter. Drops imports and bare string statements (docstrings)."""

    def __init__(self, bound: set[str]) -> None:
        self.bound = bound
        self.arguments: dict[str, str] = {}

    def _rename(self, name: str) -> str:
        if name not in self.bound:
            return name
        return self.arguments.get(name, "_")

    def visit_Name(self, node: ast.Name) -> ast.Name:
        node.id = self._rename(node.id)
        return node

    def visit_arg(self, node: ast.arg) -> ast.arg:
        node.arg = self._rename(node.arg)
        node.annotation = None
        return node

    def visit_FunctionDef(self, node: ast.FunctionDef) -> ast.FunctionDef:
        arguments = node.args.posonlyargs + node.args.args + node.args.kwonlyargs
        for position, argument in enumerate(arguments):
            self.arguments.setdefault(argument.arg, f"a{position}")
        node.name = self._rename(node.name)
        node.returns = None
        return self.generic_visit(node)

    visit_AsyncFunctionDef = visit_FunctionDef

    def visit_ClassDef(self, node: ast.ClassDef) -> ast.ClassDef:
        node.name = self._rename(node.name)
        return self.generic_visit(node)

    def visit_ExceptHandler(self, node: ast.ExceptHandler) -> ast.ExceptHandler:
        if node.name:
            node.name = self._rename(node.name)
        return self.generic_visit(node)

    def visit_Import(self, node: ast.Import) -> None:
        return None

    visit_ImportFrom = visit_Import

    def visit_Expr(self, node: ast.Expr) -> ast.Expr | None:
        if isinstance(node.value, ast.Constant) and isinstance(node.value.value, str):
            return None
        return self.generic_visit(node)


def _bound_names(tree: ast.AST, keep: set[str]) -> set[str]:
    """The names a piece of code binds (assigns, takes as arguments, defines), except ``keep``."""
    bound = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and isinstance(node.ctx, (ast.Store, ast.Del)):
            bound.add(node.id)
        elif isinstance(node, ast.arg):
            bound.add(node.arg)
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            bound.add(node.name)
        elif isinstance(node, ast.ExceptHandler) and node.name:
            bound.add(node.name)
    return bound - keep


def normalise_code(code: str, keep: set[str] = frozenset()) -> str | None:
    """Code with comments, docstrings, imports and formatting dropped and the names it binds
    canonicalised, except ``keep`` (the blank's name). None if it is not valid Python or is nested too deep to read."""
    lines = [line for line in code.splitlines() if not line.lstrip().startswith(("%", "!"))]
    try:
        tree = ast.parse("\n".join(lines))
        tree = _Canonical(_bound_names(tree, set(keep))).visit(tree)
        for node in ast.walk(tree):
            if isinstance(getattr(node, "body", None), list) and not node.body:
                node.body = [ast.Pass()]  # its only statements were imports or docstrings
        return ast.unparse(ast.fix_missing_locations(tree))
    except (SyntaxError, ValueError, RecursionError, MemoryError):  # not Python, a null byte, or nested too deep
        return None


def _token_count(source: str, cell_type: str) -> int:
    """The tokens of an answer that parsing and comparing cost: Python's tokens but comments and line
    breaks for code (the regular expression's words and symbols where it does not tokenize), words
    and symbols for text."""
    if cell_type == "code":
        skipped = {tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT, tokenize.ENDMARKER}
        try:
            return sum(token.type not in skipped for token in tokenize.generate_tokens(io.StringIO(source).readline))
        except (tokenize.TokenError, SyntaxError):
            pass
    return len(tokens(source))


def normalise_text(text: str) -> str:
    """A written answer as lower-case words and symbols, one space apart."""
    return " ".join(tokens(text.lower()))


def tokens(normalised: str) -> list[str]:
    return re.findall(r"\w+|[^\w\s]", normalised)


def normalise(source: str, cell_type: str, blank: str) -> str | None:
    """The answer to ``blank`` in a cell of this type, normalised (None: not valid Python)."""
    if cell_type == "code":
        return normalise_code(source, {blank})
    return normalise_text(source)


@dataclass(frozen=True)
class Pair:
    """Two students whose answers to one blank are alike."""

    lab: str
    blank: str
    student_a: str
    student_b: str
    score: float
    tokens: int
    """The length of the shorter answer, in tokens: short answers are alike by necessity."""
    model_answer: bool
    """Both answers are the model answer, after normalisation."""


@dataclass(frozen=True)
class Group:
    """The students who gave one answer to a blank (identical after normalisation)."""

    lab: str
    blank: str
    students: tuple[str, ...]
    tokens: int
    model_answer: bool

    @property
    def name(self) -> str:
        others = len(self.students) - 1
        return f"{self.students[0]} (and {others} with the same answer)" if others else self.students[0]


@dataclass
class Report:
    pairs: list[Pair]
    """Every pair of students listed, best first within each lab and blank."""
    groups: list[Group]
    """Answers given by two or more students."""
    near: list[tuple[Group, Group, float]]
    """Two different answers to a blank that are alike, and their score."""
    not_compared: list[str]
    """Notebooks that could not be read, and answers that are not valid Python."""


def _submissions(folder: Path) -> Path:
    """``folder/submitted`` for an nbgrader course folder, else ``folder`` itself."""
    return folder / "submitted" if (folder / "submitted").is_dir() else folder


def read_answers(folder: Path, labs: list[Lab]) -> tuple[dict[tuple[str, str], dict[str, str]], list[str]]:
    """(lab, blank) -> student -> normalised answer, from ``folder/<student>/<lab>/<lab>.ipynb``
    (or an nbgrader course folder's ``submitted/``), and the notebooks and answers not compared.
    Answers left as the release's stub are not answers and are left out."""
    answers: dict[tuple[str, str], dict[str, str]] = {}
    not_compared: list[str] = []
    for lab in labs:
        release = [c for c in cells.read(lab.release_notebook).cells if cells.is_answer(c)]
        stubs = {cells.grade_id(c): normalise(c.source, c.cell_type, cells.grade_id(c)) for c in release}
        for path in sorted(_submissions(folder).glob(f"*/{lab.id}/{lab.notebook_name}")):
            student = path.parent.parent.name
            if (size := path.stat().st_size) > MAX_SUBMISSION_BYTES:
                not_compared.append(f"{path}: {size:,} bytes, more than the {MAX_SUBMISSION_BYTES:,} the grader reads")
                continue
            try:
                found = [(cells.grade_id(c), c.source, c.cell_type) for c in cells.read(path).cells
                         if cells.is_answer(c) and cells.meta(c).get("grade_id") in stubs]
            except Exception as error:  # a submission can be any file: not JSON, truncated, not a notebook
                not_compared.append(f"{path}: not a readable notebook ({type(error).__name__})")
                continue
            for blank, source, cell_type in found:
                if len(source) > MAX_READ_CHARS or (size := _token_count(source, cell_type)) > MAX_COMPARED_TOKENS:
                    held = (f"{len(source):,} characters" if len(source) > MAX_READ_CHARS
                            else f"{size:,} tokens besides its comments")
                    not_compared.append(f"{path}: the answer to {blank} holds {held}, more than the report compares "
                                        f"({MAX_COMPARED_TOKENS:,} tokens of at most {MAX_READ_CHARS:,} characters)")
                    continue
                answer = normalise(source, cell_type, blank)
                if answer is None:
                    not_compared.append(f"{path}: the answer to {blank} is not valid Python, or is nested deeper than the report reads")
                elif answer not in (stubs[blank], normalise_text(TEXT_STUB)):
                    answers.setdefault((lab.id, blank), {})[student] = answer
    return answers, not_compared


def compare(folder: Path, labs: list[Lab] | None = None, threshold: float = THRESHOLD) -> Report:
    """Every pair of students whose answers to a blank score at least ``threshold``."""
    labs = labs or all_labs()
    answers, not_compared = read_answers(folder, labs)
    models = {}
    for lab in labs:
        for cell in cells.read(lab.source_notebook).cells:
            if cells.is_answer(cell):
                blank = cells.grade_id(cell)
                models[(lab.id, blank)] = normalise(cells.model_answer(cell), cell.cell_type, blank)
    pairs, groups, near = [], [], []
    for (lab_id, blank), by_student in sorted(answers.items()):
        alike: dict[str, list[str]] = {}
        for student, answer in sorted(by_student.items()):
            alike.setdefault(answer, []).append(student)
        model = models.get((lab_id, blank))
        distinct = [Group(lab_id, blank, tuple(students), len(tokens(answer)), answer == model)
                    for answer, students in alike.items()]
        for group in distinct:
            if len(group.students) > 1:
                groups.append(group)
            pairs += [Pair(lab_id, blank, a, b, 1.0, group.tokens, group.model_answer)
                      for a, b in combinations(group.students, 2)]
        for (one, group_one), (two, group_two) in combinations(zip(alike, distinct), 2):
            matcher = difflib.SequenceMatcher(None, tokens(one), tokens(two), autojunk=False)
            if matcher.real_quick_ratio() < threshold or matcher.quick_ratio() < threshold:
                continue
            score = round(matcher.ratio(), 3)
            if score >= threshold:
                near.append((group_one, group_two, score))
                pairs += [Pair(lab_id, blank, *sorted((a, b)), score, min(group_one.tokens, group_two.tokens), False)
                          for a in group_one.students for b in group_two.students]
    pairs.sort(key=lambda p: (p.lab, p.blank, -p.score, p.student_a, p.student_b))
    near.sort(key=lambda n: (n[0].lab, n[0].blank, -n[2]))
    return Report(pairs, groups, near, not_compared)


def write_csv(report: Report, path: Path) -> None:
    """One row per pair of students, text that a spreadsheet would read as a formula neutralised (``csv_cells``)."""
    with open(path, "w", newline="") as handle:
        writer = csv_cells.writer(handle)
        writer.writerow(["lab", "blank", "student_a", "student_b", "score", "tokens", "model_answer"])
        for p in report.pairs:
            writer.writerow([p.lab, p.blank, p.student_a, p.student_b, f"{p.score:g}", p.tokens, "yes" if p.model_answer else ""])


def print_report(report: Report) -> None:
    """Per lab and blank: the answers several students gave, then the different answers that are alike."""
    print("Similar answers, for review (normalised code; this changes no grade).")
    keys = sorted({(g.lab, g.blank) for g in report.groups} | {(a.lab, a.blank) for a, _, _ in report.near})
    for key in keys:
        print(f"{key[0]} / {key[1]}")
        for group in report.groups:
            if (group.lab, group.blank) == key:
                note = ", the model answer" if group.model_answer else ""
                print(f"  identical ({len(group.students)} students{note}): {', '.join(group.students)}")
        for one, two, score in report.near:
            if (one.lab, one.blank) == key:
                print(f"  {score:.2f}  {one.name} ~ {two.name}  ({min(one.tokens, two.tokens)} tokens)")
    for line in report.not_compared:
        print(f"not compared: {line}")
    if not keys:
        print("No two answers alike.")


def run_similarity(folder: Path, threshold: float = THRESHOLD, out: Path | None = None) -> int:
    """``python -m autograder similarity``: print the report, and write it as CSV to ``out``."""
    if not folder.is_dir():
        print(f"similarity: there is no folder {folder}")
        return 2
    report = compare(folder, threshold=threshold)
    print_report(report)
    if out:
        write_csv(report, out)
        print(f"Pairs: {out}")
    return 0

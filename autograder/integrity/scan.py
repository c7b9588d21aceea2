"""Suspicious code in a submission, found before grading and flagged for the instructor's review.

Grading no longer depends on it for correctness. The hidden tests compare in the grader's process
(autograder/pipeline/check_runner.py), so nothing the student's kernel does can change a verdict; the sandbox
(autograder/kernel/sandbox.py) keeps the kernel from the reference's files, the gradebook and other
students' folders. What the scan adds is a record: an attempt to cheat is worth an instructor's
attention even when it gained nothing, and where the OS cannot sandbox the kernel, the scan's
findings are the defence against reading the reference's files.

``static_findings(nb, lab)`` scans the syntax trees of the answer cells and of any code cell the
student added (IPython magics included, as IPython transforms them). It finds routes to the
reference (``import``, ``importlib``, ``__import__``, ``sys.modules``, ``sys.path``, reads of its
files, ``exec``/``eval``/``compile``), tampering with IPython (``get_ipython``, magics,
``sys.excepthook``), monkeypatching of modules and helpers, comparison and conversion dunders
(``__eq__``, ``__array__``, ...) on classes a blank returns, stack-frame walking, file writes
outside the submission's folder, shell commands, and try/except blocks that swallow every error of
a whole cell.

Each ``Finding`` names the blanks whose points it games: a trick inside one blank's answer games
that blank; tampering with shared machinery (NumPy, the check helpers, IPython, builtins, the
gradebook) games every blank (``None``); something suspicious that games nothing (a helper of the
visible checks redefined, a cell wrapped in a try/except that discards every error) has ``()``:
it is flagged for review and costs no points. ``FlagCheating`` (autograder/integrity/flag.py) zeroes
the test cells of the blanks a finding games, and flags the submission with the reasons.

The scan parses code in the grader's process, where IPython's transform of magics costs time that
grows with magic lines times lines, and a syntax tree costs hundreds of bytes per character: so it
parses a cell of at most MAX_SCANNED_CELL_CHARS characters, and at most MAX_SCANNED_CHARS of a
notebook's code in all. A cell beyond either is not parsed; it is a finding that costs every blank
(unscanned code could do anything the scan looks for). The grader runs the whole scan in a child
process capped in CPU time and memory (autograder/integrity/confined.py).

Edited and deleted test cells need no detector: the sanitize step (RestoreLabCells, then
nbgrader's OverwriteCells) restores them from the gradebook. Hard-coded answers for the visible
cases need none either: the hidden tests use random inputs.
"""

from __future__ import annotations

import ast
import functools
from dataclasses import dataclass
from pathlib import Path

from nbformat import NotebookNode

from autograder import cells
from autograder.integrity.rules import (
    BUILTIN_NAMES,
    KNOWN_MODULE_NAMES,
    NAMESPACE_CALLS,
    NAMESPACE_NAME_USES,
    NAMESPACE_WRITES,
    is_check_helper,
)
from autograder.integrity.syntax import bound_names, catches_everything, does_nothing, local_names, parse, single_values
from autograder.integrity.visitor import Visitor
from autograder.integrity.walker import Definitions, Hit, Walker
from autograder.labs import Lab


MAX_SCANNED_CELL_CHARS = 100_000
"""The most code of one cell that the scan parses (a lab's largest answer cell is about 6,000)."""
MAX_SCANNED_CHARS = 500_000
"""The most code of one notebook that the scan parses in all (a solved notebook has about 27,000)."""


@dataclass(frozen=True)
class Finding:
    """One reason to doubt a submission."""

    cell: str
    """The grade_id of the cell where it was found ("" if unknown)."""
    blanks: tuple[str, ...] | None
    """The blanks whose points it games; None means every autograded blank of the lab."""
    reason: str
    """One sentence for the instructor's review."""


def static_findings(nb: NotebookNode, lab: Lab) -> list[Finding]:
    """Findings from the answer cells and student-added code cells of ``nb``, before execution.

    Locked cells (given code, visible checks, test cells) are not scanned: nbgrader restores them
    from the gradebook before grading, whatever the submission holds.
    """
    path = lab.source_notebook
    scan = Scan(nb, _source_notebook(str(path), path.stat().st_mtime_ns))
    return scan.unscanned + scan.findings()


@functools.lru_cache(maxsize=16)
def _source_notebook(path: str, mtime_ns: int) -> NotebookNode:
    return cells.read(Path(path))


def _public_name(node: ast.AST) -> bool:
    """Whether ``node`` is a constant name without a leading underscore (not ``__builtins__``)."""
    return isinstance(node, ast.Constant) and isinstance(node.value, str) and not node.value.startswith("_")


def _namespace_use(name: str, call: ast.Call, parents: dict[ast.AST, ast.AST]) -> tuple[str, str] | None:
    """(kind, what) for the call ``name()`` of a namespace (globals, vars, locals), whose syntax tree's
    parents are ``parents``, or None where only its names, or a value by a public name, are used
    (Scan._namespace_uses)."""
    parent = parents.get(call)
    if isinstance(parent, ast.Subscript) and parent.value is call:
        key = parent.slice.value if isinstance(parent.slice, ast.Constant) else None
        if isinstance(parent.ctx, (ast.Store, ast.Del)) or _public_name(parent.slice):
            return None
        return "reference", f"reads {key!r} from {name}()" if isinstance(key, str) else f"reads from {name}() by a computed name"
    if isinstance(parent, ast.Attribute) and parent.value is call:
        getter = parents.get(parent)
        if parent.attr == "keys" or (parent.attr == "get" and isinstance(getter, ast.Call) and getter.func is parent
                                     and getter.args and _public_name(getter.args[0])):
            return None
        return "shared" if parent.attr in NAMESPACE_WRITES else "reference", f"uses {name}().{parent.attr}"
    if ((isinstance(parent, ast.Call) and isinstance(parent.func, ast.Name) and parent.func.id in NAMESPACE_NAME_USES)
            or (isinstance(parent, ast.Compare) and call in parent.comparators)
            or (isinstance(parent, (ast.For, ast.comprehension)) and parent.iter is call)):
        return None
    return "reference", f"takes {name}() as a whole"


def _too_large(cell: str, size: int) -> Finding:
    where = f"cell {cell}" if cell else "a cell the student added"
    return Finding(cell, None, f"The scan did not read {where}: it holds {size:,} characters of code, more than "
                               f"the {MAX_SCANNED_CELL_CHARS:,} the scan reads of one cell, so nothing checked what it does.")


def _beyond_notebook_cap(labels: list[str], scanned: int) -> Finding:
    named = [label or "a cell the student added" for label in labels]
    shown = ", ".join(named[:5]) + (f" and {len(named) - 5} more" if len(named) > 5 else "")
    return Finding("", None, f"The scan stopped after {scanned:,} characters of the notebook's code (it reads "
                             f"{MAX_SCANNED_CHARS:,} in all) and did not read {len(named)} cells ({shown}), "
                             "so nothing checked what they do.")


class Scan:
    def __init__(self, nb: NotebookNode, source_nb: NotebookNode):
        self.blanks = cells.blank_names(source_nb)
        known = {cells.grade_id(c): c for c in source_nb.cells if cells.meta(c).get("grade_id")}
        self.cells: list[tuple[str, str | None, ast.Module]] = []  # (label, blank of the answer cell, tree)
        self.unscanned: list[Finding] = []  # cells too large to parse
        scanned, beyond = 0, []
        locked_trees = []
        for cell in source_nb.cells:
            if cell.cell_type == "code" and not cells.is_answer(cell):
                tree = parse(cell.source)
                if tree is not None:
                    locked_trees.append(tree)
        for cell in nb.cells:
            if cell.get("cell_type") != "code":
                continue
            gid = cells.meta(cell).get("grade_id", "") if isinstance(cells.meta(cell), dict) else ""
            original = known.get(gid)
            if original is not None and not cells.is_answer(original):
                continue  # locked: restored by nbgrader
            if original is not None and original.cell_type != "code":
                continue  # a written answer turned into code: nbgrader turns it back
            source = cell.source if isinstance(cell.source, str) else "".join(cell.source)
            if len(source) > MAX_SCANNED_CELL_CHARS:
                self.unscanned.append(_too_large(gid or "", len(source)))
                continue
            if scanned + len(source) > MAX_SCANNED_CHARS:
                beyond.append(gid or "")
                continue
            scanned += len(source)
            tree = parse(source)
            if tree is None:
                continue
            blank = gid if original is not None and gid in self.blanks else None
            self.cells.append((gid or "", blank, tree))
        if beyond:
            self.unscanned.append(_beyond_notebook_cap(beyond, scanned))
        self.modules: dict[str, str] = {}  # name bound by an import -> dotted module or object path
        self.locked_imports: dict[str, str] = {}
        for tree in locked_trees:
            self._collect_imports(tree, self.locked_imports)
        self.modules.update(self.locked_imports)
        for _, _, tree in self.cells:
            self._collect_imports(tree, self.modules)
        # where the cells' own code first defines a name at module level, (cell, line): from there on the
        # name is the notebook's own. A method or a nested function of a builtin's name (``class T: def
        # exec(self)``) does not count, nor a definition after the code that uses the name, nor one of a
        # name that is also bound otherwise or deleted anywhere (``del exec``, ``exec = ...``, an import)
        self.defined: dict[str, tuple[int, int]] = {}
        for order, (_, _, tree) in enumerate(self.cells):
            for node in tree.body:
                if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                    self.defined.setdefault(node.name, (order, node.lineno))
        rebound = frozenset(name for _, _, tree in self.cells for name in _bound_otherwise(tree))
        trees = tuple(tree for _, _, tree in self.cells)
        self.definitions = Definitions(self.defined, rebound, single_values(list(trees)), trees)
        self.builtin_aliases = self._collect_aliases()
        self.uses = self._top_level_uses()
        self.hits: list[Hit] = []

    # -- set-up ----------------------------------------------------------------------------------

    @staticmethod
    def _collect_imports(tree: ast.AST, into: dict[str, str]) -> None:
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.asname:
                        into[alias.asname] = alias.name
                    else:
                        top = alias.name.split(".")[0]
                        into[top] = top
            elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                for alias in node.names:
                    if alias.name != "*":
                        into[alias.asname or alias.name] = f"{node.module}.{alias.name}"

    def _collect_aliases(self) -> dict[str, str]:
        """Plain aliases ``a = b`` (and parameters whose default is a name, ``def f(o=open)``) anywhere
        in the cells, followed so that the rules see through them:
        an alias of a module (``x = sys``, or an imported name) goes into ``modules``; an alias of a
        builtin (``o = open``, ``g = getattr``) is returned, alias -> builtin."""
        aliases: dict[str, str] = {}
        for _, _, tree in self.cells:
            for node in ast.walk(tree):
                for alias, value in _plain_bindings(node):
                    name = value.id
                    if name in self.modules or name in KNOWN_MODULE_NAMES:
                        self.modules.setdefault(alias, self.modules.get(name, name))
                    elif name in BUILTIN_NAMES and name not in self.defined:  # an alias of the notebook's own is its own
                        aliases[alias] = aliases.get(name, name)
        # and an alias of a module that another holds: x = np.os, x = getattr(np, "os")
        reader = Walker("", [], self.modules, self.definitions, aliases)
        for _, _, tree in self.cells:
            for node in ast.walk(tree):
                if isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name) \
                        and isinstance(node.value, (ast.Attribute, ast.Call)):
                    path = reader.module_of(node.value)
                    if path is not None:
                        self.modules.setdefault(node.targets[0].id, path)
        return aliases

    def _top_level_uses(self) -> dict[str, set[str]]:
        """Top-level name -> the global names its definition refers to (all cells, all definitions)."""
        uses: dict[str, set[str]] = {}
        for _, _, tree in self.cells:
            for stmt in tree.body:
                names = {n.id for n in ast.walk(stmt) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)}
                if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                    names -= local_names(stmt)
                for bound in bound_names(stmt):
                    uses.setdefault(bound, set()).update(names)
        return uses

    def _closure(self, name: str) -> set[str]:
        """The global names a blank uses, through helpers but not through other blanks: the hidden
        tests give each blank the reference's version of every other blank."""
        seen, todo = set(), [name]
        while todo:
            current = todo.pop()
            for used in self.uses.get(current, ()):
                if used not in seen and used not in self.blanks:
                    seen.add(used)
                    todo.append(used)
        return seen

    # -- results ---------------------------------------------------------------------------------

    def findings(self) -> list[Finding]:
        for order, (label, blank, tree) in enumerate(self.cells):
            Visitor(label, self.hits, self.modules, self.definitions, self.builtin_aliases, order).run(tree)
            self._swallow_all(label, tree)
            self._rebinds_helpers(label, tree)
            self._namespace_uses(label, tree, order)
        out: list[Finding] = []
        seen = set()
        for hit in self.hits:
            line = getattr(hit.node, "lineno", None)
            what = hit.what if hit.cell else f"in a cell the student added, {hit.what}"
            reason = what[0].upper() + what[1:] + (f" (line {line})." if line else ".")
            blank = next((b for label, b, _ in self.cells if label == hit.cell), None)
            finding = Finding(hit.cell, self._blanks(hit, blank), reason)
            if (finding.cell, finding.reason) not in seen:
                seen.add((finding.cell, finding.reason))
                out.append(finding)
        return out

    def _blanks(self, hit: Hit, cell_blank: str | None) -> tuple[str, ...] | None:
        if hit.kind == "shared":
            return None
        if hit.kind == "none":
            return ()
        if hit.owner is not None:
            entry = {hit.owner}
        elif isinstance(hit.top, ast.ImportFrom) and any(a.name == "*" for a in hit.top.names):
            return None
        else:
            entry = set(bound_names(hit.top)) if hit.top is not None else set()
        if entry & set(self.blanks):
            return tuple(b for b in self.blanks if b in entry)
        charged = [b for b in self.blanks if self._closure(b) & entry]
        if charged:
            return tuple(charged)
        if cell_blank is not None:
            return (cell_blank,)
        return None

    # -- whole-cell rules --------------------------------------------------------------------------

    def _swallow_all(self, label: str, tree: ast.Module) -> None:
        body = [s for s in tree.body if not (isinstance(s, ast.Expr) and isinstance(s.value, ast.Constant))]
        if len(body) != 1 or not isinstance(body[0], ast.Try):
            return
        for handler in body[0].handlers:
            if catches_everything(handler) and all(does_nothing(s) for s in handler.body):
                self.hits.append(Hit(label, body[0], "none", "wraps the whole cell in a try/except that discards "
                                      "every error, so the cell can never fail", body[0], None))
                return

    def _namespace_uses(self, label: str, tree: ast.Module, order: int) -> None:
        """globals(), vars() and locals() used for anything but their names: the values hold
        ``__builtins__`` (exec, open, __import__), which no plain name reaches. Allowed: ``len``,
        ``sorted`` and the like, ``in``, iteration, ``.keys()``, and a key that is a constant name
        without leading underscores. (Writes by subscript are the store rules'.)"""
        for stmt in tree.body:
            parents = {child: node for node in ast.walk(stmt) for child in ast.iter_child_nodes(node)}
            # inside a function, locals() and vars() hold that function's variables only, no __builtins__
            in_functions = {inner for scope in ast.walk(stmt) if isinstance(scope, (ast.FunctionDef, ast.AsyncFunctionDef,
                                                                                   ast.Lambda)) for inner in ast.walk(scope)}
            for node in parents:
                if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in NAMESPACE_CALLS
                        and not self.definitions.own_before(node.func.id, order, stmt.lineno)
                        and not (node.func.id == "vars" and node.args)
                        and not (node.func.id in ("locals", "vars") and node in in_functions)):
                    continue
                found = _namespace_use(node.func.id, node, parents)
                if found is not None:
                    kind, what = found
                    self.hits.append(Hit(label, node, kind, f"{what}, which reaches the values of the notebook's "
                                          "namespace, __builtins__ among them", stmt, None))

    def _rebinds_helpers(self, label: str, tree: ast.Module) -> None:
        for stmt in tree.body:
            if isinstance(stmt, (ast.Import, ast.ImportFrom)):
                fresh: dict[str, str] = {}
                self._collect_imports(stmt, fresh)
                names = [n for n, target in fresh.items()
                         if n in self.locked_imports and self.locked_imports[n] != target]
            else:
                names = [n for n in bound_names(stmt) if n in self.locked_imports]
            names = [n for n in names if is_check_helper(self.locked_imports[n])]
            for name in names:
                self.hits.append(Hit(label, stmt, "none", f"redefines {name}, which the given code imports "
                                      f"({self.locked_imports[name]}); visible checks that use it stop checking, "
                                      "hidden tests are unaffected", stmt, None))


def _plain_bindings(node: ast.AST) -> list[tuple[str, ast.Name]]:
    """(name, value) for each name that ``node`` binds to another name: ``a = b``, and a function's
    parameters whose default is a name."""
    if isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name) \
            and isinstance(node.value, ast.Name):
        return [(node.targets[0].id, node.value)]
    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
        args = node.args
        positional = args.posonlyargs + args.args
        pairs = list(zip(positional[len(positional) - len(args.defaults):], args.defaults))
        pairs += [(a, d) for a, d in zip(args.kwonlyargs, args.kw_defaults) if d is not None]
        return [(a.arg, d) for a, d in pairs if isinstance(d, ast.Name)]
    return []


def _bound_otherwise(tree: ast.AST) -> set[str]:
    """The names that ``tree`` binds or unbinds otherwise than by a definition: assignments and
    deletions (anywhere), imports, ``global`` declarations, loop and ``with`` targets."""
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and isinstance(node.ctx, (ast.Store, ast.Del)):
            names.add(node.id)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            names.update((a.asname or a.name).split(".")[0] for a in node.names)
        elif isinstance(node, ast.Global):
            names.update(node.names)
    return names

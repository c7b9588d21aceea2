"""Walking one cell's syntax tree for the scan, with the context each rule needs."""

from __future__ import annotations

import ast
from dataclasses import dataclass, field

from autograder.integrity.rules import KNOWN_MODULE_NAMES, REEXPORTED_MODULES
from autograder.integrity.syntax import fold, local_names


@dataclass
class Hit:
    """A rule broken at ``node`` of cell ``cell``: what it does, and whose points it games."""

    cell: str
    node: ast.AST
    kind: str  # "reference": charge the blanks that use it; "shared": every blank; "none": no points
    what: str
    top: ast.stmt | None
    owner: str | None


@dataclass(frozen=True)
class Definitions:
    """Where the cells' own code first defines each name at module level, (cell, line), and the names
    also bound otherwise or deleted anywhere (``del exec``, ``exec = ...``, an import)."""

    first: dict[str, tuple[int, int]]
    rebound: frozenset[str]
    values: dict[str, ast.AST] = field(default_factory=dict)
    """Names bound exactly once in the notebook, by ``name = value``: name -> value (syntax.single_values)."""
    trees: tuple[ast.Module, ...] = ()
    """Every scanned cell's tree, for what the notebook passes to its own functions."""

    def own_before(self, name: str, order: int, line: int) -> bool:
        """Whether ``name``, used in the statement at ``line`` of the ``order``-th cell, is a function or
        class the notebook defined at module level before it, and never bound otherwise."""
        first = self.first.get(name)
        return first is not None and name not in self.rebound and (order, line) > first


@dataclass
class Context:
    top: ast.stmt | None = None
    owner: str | None = None
    params: tuple[frozenset, ...] = ()
    allowed: frozenset = frozenset()


class Walker:
    """Walks one cell's tree with its context (top-level statement, enclosing def, parameters) and calls
    a ``visit_<Node>`` method for each node; the rules (autograder/integrity/visitor.py) define them."""

    def __init__(self, cell: str, hits: list[Hit], modules: dict[str, str], defined: Definitions,
                 builtin_aliases: dict[str, str], order: int = 0):
        self.cell = cell
        self.order = order
        """The cell's place among the scanned cells, which run in this order."""
        self.hits = hits
        """Where each rule broken is recorded: the scan's list (autograder/integrity/scan.py)."""
        self.modules = modules
        """Name bound by an import in the notebook -> dotted module or object path."""
        self.defined = defined
        """The functions and classes the notebook's scanned cells define at module level, and where."""
        self.builtin_aliases = builtin_aliases
        """Name bound to a builtin in the notebook (``o = open``) -> the builtin's name."""
        self.skip: set[int] = set()  # ids of nodes already handled (magic calls' get_ipython)
        self.docstrings: set[int] = set()

    def run(self, tree: ast.Module) -> None:
        for node in ast.walk(tree):
            if isinstance(node, (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                if node.body and isinstance(node.body[0], ast.Expr) and isinstance(node.body[0].value, ast.Constant):
                    self.docstrings.add(id(node.body[0].value))
        for stmt in tree.body:
            owner = stmt.name if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) else None
            self.visit(stmt, Context(top=stmt, owner=owner))

    def hit(self, node, kind, what, context):
        self.hits.append(Hit(self.cell, node, kind, what, context.top, context.owner))

    def visit(self, node: ast.AST, context: Context) -> None:
        if id(node) in self.skip:
            return
        method = getattr(self, "visit_" + type(node).__name__, None)
        if method is not None and method(node, context) is False:
            return
        inner = context
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            args = node.args
            params = {a.arg for a in args.posonlyargs + args.args + args.kwonlyargs}
            params |= {a.arg for a in (args.vararg, args.kwarg) if a is not None}
            if not isinstance(node, ast.Lambda):  # and what its body binds: a nested ``def open`` is its own there
                params |= local_names(node)
            inner = Context(context.top, context.owner, context.params + (frozenset(params),), context.allowed)
        for child in ast.iter_child_nodes(node):
            self.visit(child, inner)

    def shadowed(self, name: str, context: Context) -> bool:
        """Whether ``name`` here is the notebook's own, not a builtin's: a parameter or a name its
        enclosing function binds, or a module-level definition that comes before this statement and
        is never rebound or deleted (a method or nested function of the name does not count)."""
        if any(name in p for p in context.params):
            return True
        return context.top is not None and self.defined.own_before(name, self.order, context.top.lineno)

    def module_of(self, node: ast.AST) -> str | None:
        """The dotted path an expression names, if it is rooted at an imported name (np.testing -> numpy.testing)."""
        parts = []
        while True:
            if isinstance(node, ast.Attribute):
                parts.append(node.attr)
                node = node.value
            elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and len(node.args) >= 2
                  and self.builtin_aliases.get(node.func.id, node.func.id) == "getattr"
                  and isinstance(fold(node.args[1]), str)):  # getattr(np, "os") is np.os
                parts.append(fold(node.args[1]))
                node = node.args[0]
            else:
                break
        if not isinstance(node, ast.Name):
            return None
        root = self.modules.get(node.id)
        if root is None:
            root = {"np": "numpy", "plt": "matplotlib.pyplot"}.get(node.id) or (
                node.id if node.id in KNOWN_MODULE_NAMES else None)
        if root is None:
            return None
        path = ".".join([root] + parts[::-1]).split(".")
        # a module another one holds (np.os.system): read from the last such module on
        inner = [i for i, part in enumerate(path) if 0 < i < len(path) - 1 and part in REEXPORTED_MODULES]
        return ".".join(path[inner[-1]:] if inner else path)

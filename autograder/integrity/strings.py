"""The scan's rules for classes (methods that fool comparisons) and strings (names of the hidden packages, the gradebook)."""

from __future__ import annotations

import ast
import pickletools

from autograder.integrity.rules import (CONTAINER_DUNDERS, FORBIDDEN_DUNDERS, HIDDEN_STRING, OBJECTS_ARE_NOT_SENT,
                                        PICKLE_CALLS, SPECIAL_BASES)
from autograder.integrity.syntax import fold
from autograder.integrity.walker import Context, Walker


def calls_when_unpickled(data: bytes) -> bool:
    """Whether ``data`` reads as a whole pickle that names or calls a function (``PICKLE_CALLS``)."""
    try:
        return any(op.name in PICKLE_CALLS for op, _, _ in pickletools.genops(data))
    except Exception:  # not a pickle: genops raises ValueError, or others on a truncated or odd one
        return False


class ClassAndStringRules(Walker):
    """Class definitions and string constants."""

    def visit_ClassDef(self, node: ast.ClassDef, context: Context):
        bases = {b.attr if isinstance(b, ast.Attribute) else getattr(b, "id", "") for b in node.bases}
        forbidden = FORBIDDEN_DUNDERS | (CONTAINER_DUNDERS if bases & SPECIAL_BASES else frozenset())
        names = set()
        for stmt in node.body:
            if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef)):
                names.add(stmt.name)
            elif isinstance(stmt, ast.Assign):
                names |= {t.id for t in stmt.targets if isinstance(t, ast.Name)}
        bad = sorted(names & forbidden)
        if bad:
            self.hit(node, "none", f"defines a class {node.name} with {', '.join(bad)}: {OBJECTS_ARE_NOT_SENT}",
                     context)

    def visit_Constant(self, node: ast.Constant, context: Context):
        if isinstance(node.value, str) and id(node) not in self.docstrings:
            self.string(node, node.value, context)
        elif isinstance(node.value, bytes) and calls_when_unpickled(node.value):
            self.hit(node, "shared", "holds bytes that read as a pickle which calls a function when loaded, code "
                                     "this scan cannot see", context)

    def visit_JoinedStr(self, node: ast.JoinedStr, context: Context):
        self.string(node, fold(node), context)

    def visit_BinOp(self, node: ast.BinOp, context: Context):
        folded = fold(node)
        if isinstance(folded, str):
            self.string(node, folded, context)

    def string(self, node: ast.AST, value, context: Context) -> None:
        if not isinstance(value, str):
            return
        if HIDDEN_STRING.search(value) or "hidden_tests" in value:
            self.hit(node, "reference", f"names the hidden package in the string {value[:60]!r}", context)
        elif "gradebook" in value.lower():
            self.hit(node, "shared", f"names the gradebook in the string {value[:60]!r}", context)
        elif value in FORBIDDEN_DUNDERS:
            self.hit(node, "none", f"names the method {value} in a string: {OBJECTS_ARE_NOT_SENT}", context)

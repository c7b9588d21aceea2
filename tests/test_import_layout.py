"""The autograder's modules import one another without circles (issue 32), read from their source.

A circle makes a module's names depend on which of its modules was imported first, and hides which one
is the lower layer. Counted are the imports a module makes when it is imported (at module level, inside
``if TYPE_CHECKING:`` too: a circle of annotations is a circle of meaning), and those of its module-level
``__getattr__``, which serves the module's own names. Imports inside other functions are not counted.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

from autograder.labs import ROOT

PACKAGE = "autograder"


def module_name(path: Path, root: Path) -> str:
    """The dotted name of the module in ``path``, below the folder ``root`` (a package by its ``__init__.py``)."""
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _import_statements(tree: ast.Module) -> list[ast.Import | ast.ImportFrom]:
    """The import statements run when the module is imported, or by its module-level ``__getattr__``."""
    found, todo = [], list(tree.body)
    while todo:
        node = todo.pop()
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            found.append(node)
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            if node.name == "__getattr__" and node in tree.body:
                todo += node.body
        else:
            todo += [child for child in ast.iter_child_nodes(node) if isinstance(child, ast.stmt)]
    return found


def imported_modules(path: Path, name: str, modules: set[str]) -> set[str]:
    """The modules among ``modules`` that the module ``name``, in ``path``, imports (see the module doc)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in _import_statements(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
            continue
        base = node.module or ""
        if node.level:
            base = ".".join([*package.split(".")[: len(package.split(".")) - node.level + 1], *filter(None, [base])])
        found |= {f"{base}.{alias.name}" if f"{base}.{alias.name}" in modules else base for alias in node.names}
    return (found & modules) - {name}


def import_graph(package: Path = ROOT / PACKAGE) -> dict[str, set[str]]:
    """Module -> the modules of the package in the folder ``package`` that it imports."""
    names = {path: module_name(path, package.parent) for path in sorted(package.rglob("*.py"))}
    modules = set(names.values())
    return {name: imported_modules(path, name, modules) for path, name in names.items()}


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Each group of modules that import one another, directly or through others (sorted; none: no circle)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found: list[list[str]] = []

    def visit(module: str) -> None:  # Tarjan's strongly connected components
        index[module] = low[module] = len(index)
        stack.append(module)
        for other in sorted(graph.get(module, ())):
            if other not in index:
                visit(other)
                low[module] = min(low[module], low[other])
            elif other in stack:
                low[module] = min(low[module], index[other])
        if low[module] == index[module]:
            group = []
            while not group or group[-1] != module:
                group.append(stack.pop())
            if len(group) > 1:
                found.append(sorted(group))

    for module in sorted(graph):
        if module not in index:
            visit(module)
    return sorted(found)


def test_no_module_of_the_autograder_imports_itself_through_others():
    assert circles(import_graph()) == []


def test_a_circle_is_found_through_type_checking_and_a_module_getattr(tmp_path):
    """The reading itself: the two kinds of circle the autograder had (walker and scan through
    ``TYPE_CHECKING``, manager and sandbox through sandbox's ``__getattr__``) are found, and an import
    inside another function is not counted."""
    package = tmp_path / PACKAGE
    package.mkdir()
    files = {
        "__init__.py": "",
        "scan.py": "from autograder.walker import Walker\n",
        "walker.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from autograder.scan import Scan\n",
        "manager.py": "from autograder.sandbox import launcher\n",
        "sandbox.py": "def __getattr__(name):\n    from autograder.manager import Manager\n    return Manager\n",
        "lazy.py": "from . import scan\n",
        "lower.py": "def late():\n    from autograder import lazy\n",
    }
    for name, text in files.items():
        (package / name).write_text(text)
    graph = import_graph(package)
    assert graph["autograder.lazy"] == {"autograder.scan"}
    assert circles(graph) == [["autograder.manager", "autograder.sandbox"], ["autograder.scan", "autograder.walker"]]



def test_readmes_layout_table_names_every_module_of_each_package_it_lists():
    """README's "Where things are" draws the layout of autograder/ (issue 32): each package's row names each
    of its modules."""
    rows = re.findall(r"^\s*\| `autograder/(\w+)/` \|(.*)$", (ROOT / "README.md").read_text(), re.MULTILINE)
    assert {package for package, _ in rows} == {p.parent.name for p in (ROOT / PACKAGE).glob("*/__init__.py")}
    unnamed = {package: sorted({p.stem for p in (ROOT / PACKAGE / package).glob("*.py")} - {"__init__"}
                               - set(re.findall(r"`(\w+)", row)))
               for package, row in rows}
    assert not any(unnamed.values()), f"modules that README's 'Where things are' does not name: {unnamed}"

"""Suspicious code in a submission, found before grading and flagged for the instructor's review.

Grading no longer depends on it for correctness. The hidden tests compare in the grader's process
(autograder/compare.py), so nothing the student's kernel does can change a verdict; the sandbox
(autograder/sandbox.py) keeps the kernel from the reference's files, the gradebook and other
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
it is flagged for review and costs no points. ``FlagCheating`` (autograder/flag_cheating.py) zeroes
the test cells of the blanks a finding games, and flags the submission with the reasons.

Edited and deleted test cells need no detector: the sanitize step (RestoreLabCells, then
nbgrader's OverwriteCells) restores them from the gradebook. Hard-coded answers for the visible
cases need none either: the hidden tests use random inputs.
"""

from __future__ import annotations

import ast
import copy
import functools
import os
import re
from dataclasses import dataclass
from pathlib import Path

from nbformat import NotebookNode

from autograder import cells
from autograder.labs import Lab


@dataclass(frozen=True)
class Finding:
    """One reason to doubt a submission."""

    cell: str
    """The grade_id of the cell where it was found ("" if unknown)."""
    blanks: tuple[str, ...] | None
    """The blanks whose points it games; None means every autograded blank of the lab."""
    reason: str
    """One sentence for the instructor's review."""


FORBIDDEN_DUNDERS = frozenset({
    "__eq__", "__ne__", "__lt__", "__le__", "__gt__", "__ge__", "__bool__", "__float__", "__int__",
    "__index__", "__complex__", "__array__", "__array_ufunc__", "__array_function__",
    "__array_interface__", "__array_struct__", "__array_priority__", "__array_wrap__",
    "__array_finalize__", "__instancecheck__", "__subclasscheck__", "__getattr__", "__getattribute__",
})
"""Methods that let a returned object fool a comparison or a conversion to an array. (Arithmetic
ones such as ``__sub__`` are allowed: the checks convert to arrays before any arithmetic.)"""
CONTAINER_DUNDERS = frozenset({"__getitem__", "__iter__", "__len__"})
"""Also forbidden on subclasses of tuple, list, dict, float, int and ndarray."""

BENIGN_COMMANDS = frozenset({"pip", "pip3", "conda", "mamba", "ls", "pwd", "echo", "which", "nvidia-smi", "date",
                             "whoami", "uname", "hostname"})
"""Shell commands an honest student leaves in a notebook: flagged, but they cost no points."""


def benign_command(command) -> bool:
    """Whether a shell command is one of BENIGN_COMMANDS, with no paths up or out, and no pipes,
    redirections, substitutions or second commands."""
    if isinstance(command, (bytes, bytearray)):
        command = os.fsdecode(bytes(command))
    if not isinstance(command, str):
        try:
            command = " ".join(os.fsdecode(part) for part in command)
        except TypeError:
            return False
    words = command.split()
    if not words or any(c in command for c in ";&|<>`$\n") or ".." in command:
        return False
    first = os.path.basename(words[0])
    if first in ("python", "python3") and words[1:3] == ["-m", "pip"]:
        first, words = "pip", words[2:]
    return first in BENIGN_COMMANDS and not any(w.startswith(("/", "~")) for w in words[1:])


# -- static --------------------------------------------------------------------------------------

HIDDEN_PACKAGES = frozenset({"solutions", "autograder"})
IMPORT_MACHINERY = frozenset({"importlib", "imp", "runpy", "pkgutil", "zipimport", "code", "codeop", "linecache",
                              "tokenize", "marshal", "_imp", "_frozen_importlib", "_frozen_importlib_external"})
SHELL_PACKAGES = frozenset({"IPython", "ipykernel", "jupyter_client", "jupyter_core", "zmq", "traitlets", "comm",
                            "nbformat", "nbgrader", "nbclient", "nbconvert", "builtins", "__builtin__"})
SYSTEM_PACKAGES = frozenset({"subprocess", "pty", "multiprocessing", "ctypes", "cffi", "signal", "atexit",
                             "threading", "_thread", "concurrent", "resource", "faulthandler", "sqlite3", "dbm",
                             "shelve", "shutil", "socket", "http", "urllib", "requests", "_posixsubprocess",
                             "posix", "nt", "sysconfig", "site"})
SYSTEM_SUBMODULES = frozenset({"unittest.mock", "mock"})

REFERENCE_ATTRIBUTES = frozenset({
    "f_back", "f_globals", "f_locals", "f_builtins", "f_code", "tb_frame", "gi_frame", "cr_frame", "ag_frame",
    "_getframe", "_current_frames", "__globals__", "__closure__", "__code__", "__subclasses__", "__self__",
    "__import__", "__loader__", "__spec__", "__file__", "__path__", "__cached__", "__wrapped__",
})
"""Attribute names that reach the hidden tests' variables or the reference, on any object."""
SHARED_ATTRIBUTES = frozenset({"__builtins__", "__setattr__", "__delattr__"})

MODULE_REFERENCE = {
    "sys": {"modules", "path", "meta_path", "path_hooks", "path_importer_cache", "_getframe", "_current_frames",
            "exc_info", "last_traceback", "last_value"},
    "inspect": {"currentframe", "stack", "trace", "getouterframes", "getinnerframes", "getsource", "getsourcelines",
                "getsourcefile", "getfile", "getmodule", "getclosurevars", "getmembers", "getframeinfo"},
    "traceback": {"walk_stack", "walk_tb"},
    "types": {"FunctionType", "CodeType", "MethodType", "LambdaType", "ModuleType"},
    "gc": {"get_objects", "get_referrers", "get_referents"},
}
"""Module attributes that are routes to the reference or to the hidden tests' variables."""
MODULE_SHARED = {
    "sys": {"excepthook", "displayhook", "breakpointhook", "unraisablehook", "settrace", "setprofile",
            "addaudithook", "audit", "__excepthook__", "__displayhook__"},
    "os": {"system", "popen", "execl", "execle", "execlp", "execlpe", "execv", "execve", "execvp", "execvpe",
           "spawnl", "spawnle", "spawnlp", "spawnlpe", "spawnv", "spawnve", "spawnvp", "spawnvpe", "posix_spawn",
           "posix_spawnp", "fork", "forkpty", "kill", "killpg", "chdir", "fchdir", "putenv", "unsetenv", "chroot"},
}
"""Module attributes that tamper with the kernel or the machine."""
OS_FILE_WRITES = frozenset({"remove", "unlink", "rename", "renames", "replace", "rmdir", "removedirs", "makedirs",
                            "mkdir", "symlink", "link", "chmod", "chown", "lchown", "truncate", "utime", "open",
                            "write", "mkfifo", "mknod"})
OS_FILE_READS = frozenset({"listdir", "scandir", "walk", "fwalk", "stat", "lstat"})
NUMPY_READS = frozenset({"load", "loadtxt", "genfromtxt", "fromfile", "memmap", "fromregex"})
NUMPY_WRITES = frozenset({"save", "savez", "savez_compressed", "savetxt"})
PATH_READ_METHODS = frozenset({"read_text", "read_bytes"})
PATH_WRITE_METHODS = frozenset({"write_text", "write_bytes", "touch", "unlink", "symlink_to", "hardlink_to"})
PATH_GENERIC_METHODS = frozenset({"open", "rename", "replace", "mkdir", "rmdir", "chmod", "iterdir", "glob", "rglob"})
ALLOWED_MODULE_STORES = frozenset({"matplotlib.rcParams", "matplotlib.pyplot.rcParams"})

SAFE_LINE_MAGICS = frozenset({"matplotlib", "xmode", "precision", "pprint", "who", "whos", "who_ls", "pinfo",
                              "pinfo2", "psearch", "lsmagic", "magic", "time", "timeit", "autoreload", "history",
                              "debug", "pdb", "tb", "page"})
SAFE_CELL_MAGICS = frozenset({"time", "timeit", "capture", "debug"})
CODE_MAGICS = frozenset({"time", "timeit", "debug"})
MAGIC_CALLS = frozenset({"run_line_magic", "run_cell_magic", "system", "getoutput"})

SPECIAL_BASES = frozenset({"tuple", "list", "dict", "float", "int", "ndarray", "str", "complex"})
DUNDER_GLOBALS = frozenset({"__builtins__", "__import__", "__name__", "__loader__", "__spec__", "__package__",
                            "__file__"})

_HIDDEN_STRING = re.compile(r"(?:^|[^A-Za-z0-9_])(solutions|autograder)(?:\.[A-Za-z_]|/|\\)|^(?:solutions|autograder)$")
_PROTECTED_PARTS = frozenset({"solutions", "autograder", "source", ".git", "submitted", "autograded", "feedback",
                              "release"})
_PLANTED_SUFFIXES = (".py", ".pyc", ".pth", ".so", ".ipynb")
_DB_SUFFIXES = (".db", ".sqlite", ".sqlite3")


@dataclass
class _Hit:
    cell: str
    node: ast.AST
    kind: str  # "reference" or "local": charge the blanks that use it; "shared": every blank; "none": no points
    what: str
    top: ast.stmt | None
    owner: str | None


def static_findings(nb: NotebookNode, lab: Lab) -> list[Finding]:
    """Findings from the answer cells and student-added code cells of ``nb``, before execution.

    Locked cells (given code, visible checks, test cells) are not scanned: nbgrader restores them
    from the gradebook before grading, whatever the submission holds.
    """
    path = lab.source_notebook
    return _Scan(nb, _source_notebook(str(path), path.stat().st_mtime_ns)).findings()


@functools.lru_cache(maxsize=16)
def _source_notebook(path: str, mtime_ns: int) -> NotebookNode:
    return cells.read(Path(path))


class _Scan:
    def __init__(self, nb: NotebookNode, source_nb: NotebookNode):
        self.blanks = cells.blank_names(source_nb)
        known = {cells.grade_id(c): c for c in source_nb.cells if cells.meta(c).get("grade_id")}
        self.cells: list[tuple[str, str | None, ast.Module]] = []  # (label, blank of the answer cell, tree)
        locked_trees = []
        for cell in source_nb.cells:
            if cell.cell_type == "code" and not cells.is_answer(cell):
                tree = _parse(cell.source)
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
            tree = _parse(cell.source)
            if tree is None:
                continue
            blank = gid if original is not None and gid in self.blanks else None
            self.cells.append((gid or "", blank, tree))
        self.modules: dict[str, str] = {}  # name bound by an import -> dotted module or object path
        self.locked_imports: dict[str, str] = {}
        for tree in locked_trees:
            self._collect_imports(tree, self.locked_imports)
        self.modules.update(self.locked_imports)
        for _, _, tree in self.cells:
            self._collect_imports(tree, self.modules)
        self.defined = {node.name for _, _, tree in self.cells for node in ast.walk(tree)
                        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))}
        self.uses = self._top_level_uses()
        self.hits: list[_Hit] = []

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

    def _top_level_uses(self) -> dict[str, set[str]]:
        """Top-level name -> the global names its definition refers to (all cells, all definitions)."""
        uses: dict[str, set[str]] = {}
        for _, _, tree in self.cells:
            for stmt in tree.body:
                names = {n.id for n in ast.walk(stmt) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)}
                if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                    names -= _local_names(stmt)
                for bound in _bound_names(stmt):
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
        for label, blank, tree in self.cells:
            _Visitor(self, label).run(tree)
            self._swallow_all(label, tree)
            self._rebinds_helpers(label, tree)
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

    def _blanks(self, hit: _Hit, cell_blank: str | None) -> tuple[str, ...] | None:
        if hit.kind == "shared":
            return None
        if hit.kind == "none":
            return ()
        if hit.owner is not None:
            entry = {hit.owner}
        elif isinstance(hit.top, ast.ImportFrom) and any(a.name == "*" for a in hit.top.names):
            return None
        else:
            entry = set(_bound_names(hit.top)) if hit.top is not None else set()
        if entry & set(self.blanks):
            return tuple(b for b in self.blanks if b in entry)
        charged = [b for b in self.blanks if self._closure(b) & entry]
        if charged:
            return tuple(charged)
        if cell_blank is not None:
            return (cell_blank,)
        return None

    def hit(self, cell: str, node: ast.AST, kind: str, what: str, context: "_Context") -> None:
        self.hits.append(_Hit(cell, node, kind, what, context.top, context.owner))

    # -- whole-cell rules --------------------------------------------------------------------------

    def _swallow_all(self, label: str, tree: ast.Module) -> None:
        body = [s for s in tree.body if not (isinstance(s, ast.Expr) and isinstance(s.value, ast.Constant))]
        if len(body) != 1 or not isinstance(body[0], ast.Try):
            return
        for handler in body[0].handlers:
            if _catches_everything(handler) and all(_does_nothing(s) for s in handler.body):
                self.hits.append(_Hit(label, body[0], "none", "wraps the whole cell in a try/except that discards "
                                      "every error, so the cell can never fail", body[0], None))
                return

    def _rebinds_helpers(self, label: str, tree: ast.Module) -> None:
        for stmt in tree.body:
            if isinstance(stmt, (ast.Import, ast.ImportFrom)):
                fresh: dict[str, str] = {}
                self._collect_imports(stmt, fresh)
                names = [n for n, target in fresh.items()
                         if n in self.locked_imports and self.locked_imports[n] != target]
            else:
                names = [n for n in _bound_names(stmt) if n in self.locked_imports]
            names = [n for n in names if _is_check_helper(self.locked_imports[n])]
            for name in names:
                self.hits.append(_Hit(label, stmt, "none", f"redefines {name}, which the given code imports "
                                      f"({self.locked_imports[name]}); visible checks that use it stop checking, "
                                      "hidden tests are unaffected", stmt, None))


@dataclass
class _Context:
    top: ast.stmt | None = None
    owner: str | None = None
    params: tuple[frozenset, ...] = ()
    allowed: frozenset = frozenset()


class _Visitor:
    """Walks one cell's tree with its context (top-level statement, enclosing def, parameters)."""

    def __init__(self, scan: _Scan, cell: str):
        self.scan = scan
        self.cell = cell
        self.skip: set[int] = set()  # ids of nodes already handled (magic calls' get_ipython)
        self.docstrings: set[int] = set()

    def run(self, tree: ast.Module) -> None:
        for node in ast.walk(tree):
            if isinstance(node, (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                if node.body and isinstance(node.body[0], ast.Expr) and isinstance(node.body[0].value, ast.Constant):
                    self.docstrings.add(id(node.body[0].value))
        for stmt in tree.body:
            owner = stmt.name if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) else None
            self.visit(stmt, _Context(top=stmt, owner=owner))

    def hit(self, node, kind, what, context):
        self.scan.hit(self.cell, node, kind, what, context)

    def visit(self, node: ast.AST, context: _Context) -> None:
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
            inner = _Context(context.top, context.owner, context.params + (frozenset(params),), context.allowed)
        for child in ast.iter_child_nodes(node):
            self.visit(child, inner)

    def shadowed(self, name: str, context: _Context) -> bool:
        return name in self.scan.defined or any(name in p for p in context.params)

    def module_of(self, node: ast.AST) -> str | None:
        """The dotted path an expression names, if it is rooted at an imported name (np.testing -> numpy.testing)."""
        parts = []
        while isinstance(node, ast.Attribute):
            parts.append(node.attr)
            node = node.value
        if not isinstance(node, ast.Name):
            return None
        root = self.scan.modules.get(node.id)
        if root is None:
            root = {"np": "numpy", "plt": "matplotlib.pyplot"}.get(node.id) or (
                node.id if node.id in ("sys", "os", "builtins", "numpy", "scipy", "math", "importlib", "inspect",
                                       "gc", "types", "course", "solutions", "autograder", "IPython") else None)
        if root is None:
            return None
        return ".".join([root] + parts[::-1])

    # -- imports -------------------------------------------------------------------------------

    def visit_Import(self, node: ast.Import, context: _Context):
        for alias in node.names:
            self.check_module(alias.name, node, context)

    def visit_ImportFrom(self, node: ast.ImportFrom, context: _Context):
        if node.level:
            self.hit(node, "reference", "uses a relative import, which reaches packages beside the notebook", context)
            return
        module = node.module or ""
        if self.check_module(module, node, context):
            return
        for alias in node.names:
            if alias.name != "*":
                self.check_path(f"{module}.{alias.name}", node, context, store=False)

    def check_module(self, module: str, node: ast.AST, context: _Context) -> bool:
        top = module.split(".")[0]
        if top in HIDDEN_PACKAGES:
            self.hit(node, "reference", f"imports the hidden package {module}", context)
        elif top in IMPORT_MACHINERY:
            self.hit(node, "reference", f"imports {module}, which loads or reads any module, the hidden reference "
                                        "included", context)
        elif top in SHELL_PACKAGES:
            self.hit(node, "shared", f"imports {module}, which reaches the Python and IPython machinery that runs "
                                     "the tests", context)
        elif top in SYSTEM_PACKAGES or module in SYSTEM_SUBMODULES or module.startswith("unittest.mock"):
            self.hit(node, "shared", f"imports {module}, which can run commands, patch code or change files "
                                     "during grading", context)
        else:
            return False
        return True

    # -- names and attributes ----------------------------------------------------------------------

    def visit_Name(self, node: ast.Name, context: _Context):
        name = node.id
        if isinstance(node.ctx, (ast.Store, ast.Del)) and name in DUNDER_GLOBALS:
            self.hit(node, "shared", f"rebinds the notebook's {name}", context)
        elif name == "__import__":
            self.hit(node, "reference", "calls __import__, which loads any module, the hidden reference included",
                     context)
        elif name == "__builtins__":
            self.hit(node, "shared", "reaches __builtins__, which changes what every cell and test sees", context)
        elif name in ("__loader__", "__spec__", "__file__") and isinstance(node.ctx, ast.Load):
            self.hit(node, "reference", f"uses {name} to locate files", context)
        elif name == "get_ipython" and not self.shadowed(name, context):
            self.hit(node, "shared", "reaches the IPython shell that runs the tests (get_ipython)", context)
        elif name in ("exec", "eval", "compile") and isinstance(node.ctx, ast.Load) and not self.shadowed(name, context):
            self.hit(node, "shared", f"runs code built at run time ({name}), which this scan cannot see", context)
        elif name == "globals" and isinstance(node.ctx, ast.Load) and not self.shadowed(name, context):
            self.hit(node, "reference", "reads the notebook's namespace through globals()", context)

    def visit_Attribute(self, node: ast.Attribute, context: _Context):
        store = isinstance(node.ctx, (ast.Store, ast.Del))
        path = self.module_of(node)
        if path is None:
            self.attribute_name(node, node.attr, store, module=False, context=context)
            return None
        if not store:  # a store is reported as monkeypatching below
            covered = {name for module, names in MODULE_REFERENCE.items() if path.split(".")[0] == module
                       for name in names}
            chain = node
            while isinstance(chain, ast.Attribute):  # np.__dict__.update: every link of the chain
                if chain.attr not in covered:
                    self.attribute_name(node, chain.attr, False, module=True, context=context)
                chain = chain.value
        self.check_path(path, node, context, store=store)
        return False

    def attribute_name(self, node, attr: str, store: bool, module: bool, context: _Context) -> None:
        if attr in REFERENCE_ATTRIBUTES:
            self.hit(node, "reference", f"uses .{attr}, which reaches the hidden tests' variables, their code or "
                                        "the reference's files", context)
        elif attr in SHARED_ATTRIBUTES:
            self.hit(node, "shared", f"uses .{attr}, which tampers with other objects' attributes", context)
        elif attr == "__dict__":
            if module or not isinstance(node.value, ast.Name):
                self.hit(node, "shared" if store else "reference", "reaches into a module's __dict__", context)
        elif store and (attr in FORBIDDEN_DUNDERS or attr == "__class__"):
            self.hit(node, "local", f"sets {attr} on an object, which can fool the tests' comparisons", context)

    def visit_Subscript(self, node: ast.Subscript, context: _Context):
        if not isinstance(node.ctx, (ast.Store, ast.Del)):
            return None
        container = node.value
        path = self.module_of(container)
        if path == "os.environ":
            self.hit(node, "none", "sets an environment variable, which grading ignores", context)
        elif path is not None and path not in ALLOWED_MODULE_STORES:
            self.hit(node, "shared", f"writes into {path}", context)
        elif isinstance(container, ast.Call) and isinstance(container.func, ast.Name) and container.func.id in (
                "vars", "globals") and not self.shadowed(container.func.id, context):
            if container.func.id == "globals" or (container.args and self.module_of(container.args[0]) is not None):
                self.hit(node, "shared", f"writes into a namespace through {container.func.id}()", context)
        elif isinstance(container, ast.Attribute) and container.attr == "__dict__":
            self.hit(node, "shared", "writes into an object's __dict__", context)
        return None

    def check_path(self, path: str, node: ast.AST, context: _Context, store: bool) -> None:
        """Rules for a dotted path rooted at an imported name (sys.modules, numpy.allclose, ...)."""
        parts = path.split(".")
        top = parts[0]
        if store:
            if path not in ALLOWED_MODULE_STORES:
                self.hit(node, "shared", f"monkeypatches {path}", context)
            return
        if top in HIDDEN_PACKAGES:
            self.hit(node, "reference", f"uses the hidden package {path}", context)
            return
        for module, names in MODULE_REFERENCE.items():
            if top == module and len(parts) > 1 and parts[1] in names:
                self.hit(node, "reference", f"uses {module}.{parts[1]}, a route to the hidden reference or to the "
                                            "hidden tests' variables", context)
                return
        for module, names in MODULE_SHARED.items():
            if top == module and len(parts) > 1 and parts[1] in names:
                self.hit(node, "shared", f"uses {module}.{parts[1]}, which tampers with the kernel or the machine",
                         context)
                return
        if top != "sys" and "sys" in parts[1:-1] and parts[parts.index("sys", 1) + 1] in MODULE_REFERENCE["sys"]:
            self.hit(node, "reference", f"uses {path}, sys reached through another module", context)
            return
        if top == "os" and len(parts) > 1 and parts[1] == "environ" and len(parts) > 2 and parts[2] in (
                "update", "setdefault", "pop", "clear", "__setitem__"):
            self.hit(node, "shared", "changes environment variables", context)

    # -- calls ------------------------------------------------------------------------------------

    def visit_Call(self, node: ast.Call, context: _Context):
        func = node.func
        if self.magic(node, context):
            return False
        if isinstance(func, ast.Name) and not self.shadowed(func.id, context):
            name = func.id
            if name in ("getattr", "hasattr", "setattr", "delattr") and len(node.args) >= 2:
                self.dynamic_attribute(node, name, context)
            elif name == "vars" and node.args and self.module_of(node.args[0]) is not None:
                self.hit(node, "reference", f"reads the namespace of {self.module_of(node.args[0])} through vars()",
                         context)
            elif name == "open":
                self.file_access(node, _first_arg(node, "file"), _open_writes(node, 1), context)
            elif name in ("Path", "PurePath", "PosixPath") and node.args:
                self.file_path_seen(node.args[0], node, context)
        elif isinstance(func, ast.Attribute):
            path = self.module_of(func)
            method = func.attr
            if path in ("io.open", "codecs.open"):
                self.file_access(node, _first_arg(node, "file"), _open_writes(node, 1), context)
            elif path is not None and path.startswith("os.") and path.count(".") == 1 and method in OS_FILE_WRITES:
                for arg in node.args[:2]:
                    self.file_access(node, arg, method != "open" or None, context)
            elif path is not None and path.startswith("os.") and path.count(".") == 1 and method in OS_FILE_READS:
                if node.args:
                    self.file_access(node, node.args[0], False, context)
            elif path is not None and path.startswith("shutil."):
                for arg in node.args[:2]:
                    self.file_access(node, arg, True, context)
            elif path is not None and path.split(".")[0] == "numpy" and method in NUMPY_READS | NUMPY_WRITES:
                self.file_access(node, _first_arg(node, "file"), method in NUMPY_WRITES, context)
            elif path is not None and path.startswith("sqlite3."):
                if node.args:
                    self.file_access(node, node.args[0], True, context)
            elif method in ("savefig", "tofile") and node.args:
                self.file_access(node, node.args[0], True, context)
            elif method in PATH_READ_METHODS | PATH_WRITE_METHODS:
                base = _path_constructor_arg(func.value)
                self.file_access(node, base, method in PATH_WRITE_METHODS, context, unknown_ok=False)
            elif method in PATH_GENERIC_METHODS and _path_constructor_arg(func.value) is not None:
                writes = method != "open" or _open_writes(node, 0)
                self.file_access(node, _path_constructor_arg(func.value), writes, context)
            elif method == "join" and isinstance(func.value, ast.Constant):
                self.string(node, _fold(node), context)
        return None

    def dynamic_attribute(self, node: ast.Call, name: str, context: _Context) -> None:
        target, attr = node.args[0], _fold(node.args[1])
        store = name in ("setattr", "delattr")
        if isinstance(attr, str):
            if attr in REFERENCE_ATTRIBUTES:
                self.hit(node, "reference", f"uses {name}(..., {attr!r}), which reaches the hidden tests' variables, "
                                            "their code or the reference's files", context)
            elif attr in SHARED_ATTRIBUTES or attr == "__dict__":
                self.hit(node, "shared", f"uses {name}(..., {attr!r}) to tamper with attributes", context)
            elif store and attr in FORBIDDEN_DUNDERS | {"__class__"}:
                self.hit(node, "local", f"sets {attr} with {name}, which can fool the tests' comparisons", context)
            path = self.module_of(target)
            if path is not None:
                self.check_path(f"{path}.{attr}", node, context, store=store)
        elif self.module_of(target) is not None or isinstance(target, ast.Call):
            kind = "shared" if store else "reference"
            self.hit(node, kind, f"uses {name} with a computed attribute name on {self.module_of(target) or 'an object'}",
                     context)

    def file_path_seen(self, arg: ast.AST, node: ast.AST, context: _Context) -> None:
        folded = _fold(arg)
        if isinstance(folded, str):
            why = _path_problem(folded, writing=False)
            if why:
                self.hit(node, "reference", f"builds the path {folded!r}, which {why}", context)

    def file_access(self, node, arg, writes, context, unknown_ok: bool = False) -> None:
        """A file access with path expression ``arg``; ``writes`` True, False, or None (unknown)."""
        writing = writes is not False
        kind = "shared" if writing else "reference"
        verb = "writes" if writes else ("reads" if writes is False else "opens")
        if arg is None:
            if not unknown_ok:
                self.hit(node, kind, f"{verb} a file whose name this scan cannot see", context)
            return
        folded = _fold(arg)
        if isinstance(folded, str):
            why = _path_problem(folded, writing)
            if why:
                self.hit(node, kind, f"{verb} {folded!r}, which {why}", context)
            return
        pieces = _constant_pieces(arg)
        if pieces is not None and pieces:
            for piece in pieces:
                why = _path_problem(piece, writing, fragment=True)
                if why:
                    self.hit(node, kind, f"{verb} a file named from {piece!r}, which {why}", context)
                    return
            if any(p.strip() for p in pieces):
                return  # a name like f"fig_{i}.png" in the working folder
        self.hit(node, kind, f"{verb} a file whose name is computed at run time", context)

    # -- IPython magics ---------------------------------------------------------------------------

    def magic(self, node: ast.Call, context: _Context) -> bool:
        func = node.func
        if not (isinstance(func, ast.Attribute) and func.attr in MAGIC_CALLS and isinstance(func.value, ast.Call)
                and isinstance(func.value.func, ast.Name) and func.value.func.id == "get_ipython"
                and all(isinstance(a, ast.Constant) and isinstance(a.value, str) for a in node.args)):
            return False
        args = [a.value for a in node.args]
        if func.attr in ("system", "getoutput"):
            command = args[0] if args else ""
            kind = "none" if benign_command(command) else "shared"
            self.hit(node, kind, f"runs the shell command !{command}, which grading refuses", context)
            return True
        name = args[0] if args else ""
        line = args[1] if len(args) > 1 else ""
        if func.attr == "run_line_magic" and name in ("pip", "conda", "mamba") and benign_command(f"{name} {line}"):
            self.hit(node, "none", f"runs %{name} {line}, which grading refuses", context)
            return True
        if func.attr == "run_line_magic":
            safe = (name in SAFE_LINE_MAGICS or (name == "load_ext" and line.strip() == "autoreload")
                    or (name == "config" and line.strip().startswith("InlineBackend.")))
            if safe:
                if name in CODE_MAGICS:
                    self.nested(_strip_magic_options(line), node, context)
                return True
            self.hit(node, "shared", f"runs the IPython magic %{name} {line}".rstrip(), context)
            return True
        body = args[2] if len(args) > 2 else ""
        if name in SAFE_CELL_MAGICS:
            if name in CODE_MAGICS:
                self.nested(_strip_magic_options(line), node, context)
            self.nested(body, node, context)
            return True
        self.hit(node, "shared", f"runs the IPython cell magic %%{name}", context)
        return True

    def nested(self, code: str, node: ast.AST, context: _Context) -> None:
        tree = copy.deepcopy(_parse(code))
        if tree is None:
            return
        for stmt in tree.body:
            for child in ast.walk(stmt):
                if hasattr(child, "lineno"):
                    child.lineno = getattr(node, "lineno", 1)
            self.visit(stmt, context)

    # -- classes and strings ------------------------------------------------------------------------

    def visit_ClassDef(self, node: ast.ClassDef, context: _Context):
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
            self.hit(node, "local", f"defines a class {node.name} with {', '.join(bad)}, which can fool the tests' "
                                    "comparisons and conversions of what a blank returns", context)

    def visit_Constant(self, node: ast.Constant, context: _Context):
        if isinstance(node.value, str) and id(node) not in self.docstrings:
            self.string(node, node.value, context)

    def visit_JoinedStr(self, node: ast.JoinedStr, context: _Context):
        self.string(node, _fold(node), context)

    def visit_BinOp(self, node: ast.BinOp, context: _Context):
        folded = _fold(node)
        if isinstance(folded, str):
            self.string(node, folded, context)

    def string(self, node: ast.AST, value, context: _Context) -> None:
        if not isinstance(value, str):
            return
        if _HIDDEN_STRING.search(value) or "hidden_tests" in value:
            self.hit(node, "reference", f"names the hidden package in the string {value[:60]!r}", context)
        elif "gradebook" in value.lower():
            self.hit(node, "shared", f"names the gradebook in the string {value[:60]!r}", context)
        elif value in FORBIDDEN_DUNDERS:
            self.hit(node, "local", f"names the method {value} in a string, to set it on an object", context)


# -- helpers ---------------------------------------------------------------------------------------

@functools.lru_cache(maxsize=4096)
def _parse(source: str) -> ast.Module | None:
    """The syntax tree of a cell as IPython runs it (magics become get_ipython() calls), or None.

    Cached: callers must not modify the tree.
    """
    try:
        code = _transformer().transform_cell(source)
    except Exception:
        code = source
    for attempt in (code, "\n".join(line for line in source.splitlines() if not line.lstrip().startswith(("%", "!")))):
        try:
            return ast.parse(attempt)
        except (SyntaxError, ValueError):
            continue
    return None


@functools.lru_cache(maxsize=1)
def _transformer():
    from IPython.core.inputtransformer2 import TransformerManager

    return TransformerManager()


def _bound_names(stmt: ast.AST | None) -> list[str]:
    """The names a top-level statement binds."""
    if stmt is None:
        return []
    if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
        return [stmt.name]
    if isinstance(stmt, (ast.Import, ast.ImportFrom)):
        return [(a.asname or a.name).split(".")[0] for a in stmt.names if a.name != "*"]
    targets: list[ast.AST] = []
    if isinstance(stmt, ast.Assign):
        targets = list(stmt.targets)
    elif isinstance(stmt, (ast.AugAssign, ast.AnnAssign)):
        targets = [stmt.target]
    elif isinstance(stmt, (ast.For, ast.AsyncFor)):
        targets = [stmt.target]
    elif isinstance(stmt, (ast.With, ast.AsyncWith)):
        targets = [item.optional_vars for item in stmt.items if item.optional_vars is not None]
    names = []
    for target in targets:
        names += _target_names(target)
    if isinstance(stmt, (ast.If, ast.Try, ast.While, ast.With, ast.For)):
        for child in ast.iter_child_nodes(stmt):
            if isinstance(child, ast.stmt):
                names += _bound_names(child)
        for handler in getattr(stmt, "handlers", []):
            for child in handler.body:
                names += _bound_names(child)
    return names


def _local_names(definition: ast.AST) -> set[str]:
    """Names local to a function or class body (parameters, assignments, nested definitions), minus
    those declared global."""
    local, declared = set(), set()
    for node in ast.walk(definition):
        if node is definition:
            continue
        if isinstance(node, ast.arg):
            local.add(node.arg)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, (ast.Store, ast.Del)):
            local.add(node.id)
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            local.add(node.name)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            local.update((a.asname or a.name).split(".")[0] for a in node.names)
        elif isinstance(node, (ast.Global, ast.Nonlocal)):
            declared.update(node.names)
    if isinstance(definition, (ast.FunctionDef, ast.AsyncFunctionDef)):
        args = definition.args
        local.update(a.arg for a in args.posonlyargs + args.args + args.kwonlyargs)
        local.update(a.arg for a in (args.vararg, args.kwarg) if a is not None)
    return local - declared


def _target_names(target: ast.AST) -> list[str]:
    """The names an assignment target binds (``a, (b, *c) = ...``); none for attributes and items."""
    if isinstance(target, ast.Name):
        return [target.id]
    if isinstance(target, (ast.Tuple, ast.List)):
        return [name for element in target.elts for name in _target_names(element)]
    if isinstance(target, ast.Starred):
        return _target_names(target.value)
    return []


def _fold(node: ast.AST):
    """The string value of a constant string expression, or None."""
    if isinstance(node, ast.Constant):
        return node.value if isinstance(node.value, str) else None
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Div)):
        left, right = _fold(node.left), _fold(node.right)
        if isinstance(left, str) and isinstance(right, str):
            return left + ("/" if isinstance(node.op, ast.Div) else "") + right
        return None
    if isinstance(node, ast.JoinedStr):
        parts = [_fold(v) if not isinstance(v, ast.FormattedValue) else _fold(v.value) for v in node.values]
        return "".join(parts) if all(isinstance(p, str) for p in parts) else None
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
        if node.func.attr == "join" and len(node.args) == 1 and isinstance(node.args[0], (ast.List, ast.Tuple)):
            sep = _fold(node.func.value)
            if isinstance(node.func.value, ast.Attribute) and node.func.value.attr == "path":
                sep = None
            items = [_fold(e) for e in node.args[0].elts]
            if isinstance(sep, str) and all(isinstance(i, str) for i in items):
                return sep.join(items)
        if node.func.attr == "join" and isinstance(node.func.value, ast.Attribute) and node.func.value.attr == "path":
            items = [_fold(a) for a in node.args]
            if items and all(isinstance(i, str) for i in items):
                return "/".join(items)
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in ("str", "Path") and node.args:
        return _fold(node.args[0])
    return None


def _constant_pieces(node: ast.AST) -> list[str] | None:
    """The constant string pieces of an f-string, a sum of strings or os.path.join, or None."""
    if isinstance(node, ast.JoinedStr):
        return [v.value for v in node.values if isinstance(v, ast.Constant) and isinstance(v.value, str)]
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Div)):
        pieces = []
        for side in (node.left, node.right):
            folded = _fold(side)
            if isinstance(folded, str):
                pieces.append(folded)
            else:
                inner = _constant_pieces(side)
                if inner:
                    pieces += inner
        return pieces
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "join":
        return [f for f in (_fold(a) for a in node.args) if isinstance(f, str)] or None
    return None


def _path_problem(path: str, writing: bool, fragment: bool = False) -> str | None:
    """Why a (constant) path may not be used, or None for a plain file in the working folder."""
    text = path.replace("\\", "/")
    parts = [p for p in text.split("/") if p]
    name = parts[-1] if parts else ""
    if any(p in _PROTECTED_PARTS for p in parts) or any(p.startswith(("solutions.", "autograder.")) for p in parts):
        return "is part of the course's hidden material or other students' work"
    if "gradebook" in text.lower() or name.endswith(_DB_SUFFIXES):
        return "is the gradebook"
    if ".." in parts or (not fragment and (text.startswith(("/", "~")) or re.match(r"^[A-Za-z]:", text))):
        return "is outside the submission's folder"
    if fragment and ("/" in text and text.strip("/") and (text.startswith("/") or ".." in parts)):
        return "is outside the submission's folder"
    if writing and (name == "timestamp.txt" or (not fragment and name.endswith(_PLANTED_SUFFIXES))
                    or (fragment and text.endswith(_PLANTED_SUFFIXES))):
        return "is a file that grading reads or imports"
    return None


def _is_check_helper(path: str) -> bool:
    """A helper of the visible checks that the given code imports (course.checks.check_close, ...)."""
    last = path.rsplit(".", 1)[-1]
    return path.startswith("course.") and (last.startswith("check") or last in ("require", "passed"))


def _first_arg(node: ast.Call, keyword: str) -> ast.AST | None:
    if node.args:
        return node.args[0]
    for kw in node.keywords:
        if kw.arg == keyword:
            return kw.value
    return None


def _open_writes(node: ast.Call, position: int) -> bool | None:
    """Whether an open(...) call writes: True, False, or None if its mode is not a constant."""
    mode = node.args[position] if len(node.args) > position else next(
        (kw.value for kw in node.keywords if kw.arg == "mode"), None)
    if mode is None:
        return False
    folded = _fold(mode)
    if not isinstance(folded, str):
        return None
    return any(c in folded for c in "wax+")


def _path_constructor_arg(node: ast.AST) -> ast.AST | None:
    """For ``Path(x)`` (or ``pathlib.Path(x)``, ``Path(x) / y``), the path expression; else None."""
    if isinstance(node, ast.Call):
        func = node.func
        name = func.id if isinstance(func, ast.Name) else (func.attr if isinstance(func, ast.Attribute) else "")
        if name in ("Path", "PurePath", "PosixPath") and node.args:
            return node.args[0] if len(node.args) == 1 else ast.BinOp(node.args[0], ast.Div(), node.args[1])
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Div):
        base = _path_constructor_arg(node.left)
        if base is not None:
            return ast.BinOp(base, ast.Div(), node.right)
    return None


def _catches_everything(handler: ast.ExceptHandler) -> bool:
    kinds = handler.type
    if kinds is None:
        return True
    names = kinds.elts if isinstance(kinds, ast.Tuple) else [kinds]
    return any(isinstance(n, ast.Name) and n.id in ("Exception", "BaseException") for n in names)


def _does_nothing(stmt: ast.stmt) -> bool:
    return isinstance(stmt, (ast.Pass, ast.Continue)) or (isinstance(stmt, ast.Expr) and isinstance(stmt.value, ast.Constant))


def _strip_magic_options(line: str) -> str:
    """The statement of a %time/%timeit line, without its options (-n 10 -r 3 -q ...)."""
    return re.sub(r"^(\s*-[A-Za-z](\s+(?!-)\S+)?)*\s*", "", line) if line.lstrip().startswith("-") else line

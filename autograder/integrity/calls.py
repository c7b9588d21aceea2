"""The scan's rules for calls: file access, getattr and friends, IPython magics and shell commands."""

from __future__ import annotations

import ast
import copy

from autograder.integrity.rules import (
    ATTRIBUTE_GETTERS,
    KNOWN_MODULE_NAMES,
    MODULE_REFERENCE,
    MODULE_SHARED,
    REEXPORTED_MODULES,
    BUILTIN_NAMES,
    CODE_MAGICS,
    IMAGE_READERS,
    DISPLAY_MODULE,
    DISPLAY_READERS,
    FORBIDDEN_DUNDERS,
    IN_MEMORY_FILES,
    MAGIC_CALLS,
    NUMPY_READS,
    NUMPY_WRITES,
    OBJECTS_ARE_NOT_SENT,
    OS_FILE_READS,
    OS_FILE_WRITES,
    PASSED_BUILTINS,
    PATH_GENERIC_METHODS,
    PATH_READ_METHODS,
    PATH_WRITE_METHODS,
    REFERENCE_ATTRIBUTES,
    SAFE_CELL_MAGICS,
    SAFE_LINE_MAGICS,
    SHARED_ATTRIBUTES,
    TEXT_RUNNERS,
    benign_command,
    path_problem,
)
from autograder.integrity.syntax import (
    argument_choices,
    constant_pieces,
    first_arg,
    fold,
    loop_constants,
    open_writes,
    parse,
    path_constructor_arg,
    strip_magic_options,
    substitute,
)
from autograder.integrity.walker import Context, Walker



class CallRules(Walker):
    """Calls: files opened, attributes reached by name, IPython magics and shell commands."""

    def visit_Call(self, node: ast.Call, context: Context):
        func = node.func
        if self.magic(node, context):
            return False
        for arg in [*node.args, *(kw.value for kw in node.keywords)]:  # reduce(getattr, ...), map(open, ...)
            name = self.builtin_aliases.get(arg.id, arg.id) if isinstance(arg, ast.Name) else None
            if name in PASSED_BUILTINS and (arg.id in self.builtin_aliases or not self.shadowed(arg.id, context)):
                self.hit(node, "reference", f"passes {name} to another function, where the scan cannot follow "
                                            "what it reaches", context)
        if isinstance(func, ast.Name) and (func.id in self.builtin_aliases or not self.shadowed(func.id, context)):
            name = self.builtin_aliases.get(func.id, func.id)  # o = open (or def f(o=open)): o(...) is open(...)
            if name in ("getattr", "hasattr", "setattr", "delattr") and len(node.args) >= 2:
                self.dynamic_attribute(node, name, context)
            elif name == "vars" and node.args and self.module_of(node.args[0]) is not None:
                self.hit(node, "reference", f"reads the namespace of {self.module_of(node.args[0])} through vars()",
                         context)
            elif name == "open":
                self.file_access(node, first_arg(node, "file"), open_writes(node, 1), context)
            elif name in ("Path", "PurePath", "PosixPath") and node.args:
                self.file_path_seen(node.args[0], node, context)
        if self.display_reader(func, context):
            for arg in (node.args[:1] + [kw.value for kw in node.keywords if kw.arg in ("data", "filename", "url")]):
                self.display_argument(node, arg, context)
        elif isinstance(func, ast.Attribute) or (isinstance(func, ast.Name) and func.id in self.modules
                                                   and not self.shadowed(func.id, context)):
            # os.chmod(...), and chmod(...) after ``from os import chmod``
            path = self.module_of(func)
            method = func.attr if isinstance(func, ast.Attribute) else (path or "").rpartition(".")[2]
            if path in TEXT_RUNNERS:
                self.text_runner(node, path, first_arg(node, "stmt"), context)
            if path in ATTRIBUTE_GETTERS and not all(_plain_attribute_name(arg) for arg in node.args[:1]):
                self.hit(node, "reference", f"uses {path} with a name computed at run time or a special one, which "
                                            "reaches any attribute", context)
            if path in ("io.open", "io.FileIO", "codecs.open", "numpy.lib.format.open_memmap"):
                self.file_access(node, first_arg(node, "file"), open_writes(node, 1), context)
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
                self.file_access(node, first_arg(node, "file"), method in NUMPY_WRITES, context)
            elif path is not None and path.startswith("sqlite3."):
                if node.args:
                    self.file_access(node, node.args[0], True, context)
            elif path is not None and (path.startswith("scipy.io.") or path in IMAGE_READERS):
                self.file_access(node, first_arg(node, "file_name"), method.startswith(("save", "write")), context)
            elif not isinstance(func, ast.Attribute):
                pass  # the rules below are for methods
            elif method in ("savefig", "tofile") and node.args:
                self.file_access(node, node.args[0], True, context)
            elif method in PATH_READ_METHODS | PATH_WRITE_METHODS | PATH_GENERIC_METHODS:
                # Path("x").write_text(...), and notes.write_text(...) after notes = Path("x")
                base = path_constructor_arg(substitute(func.value, self.defined.values))
                if method not in PATH_GENERIC_METHODS:
                    self.file_access(node, base, method in PATH_WRITE_METHODS, context, unknown_ok=False)
                elif base is not None:
                    self.file_access(node, base, method != "open" or open_writes(node, 0), context)
            elif method == "join" and isinstance(func.value, ast.Constant):
                self.string(node, fold(node), context)
        return None

    def text_runner(self, node: ast.Call, path: str, code: ast.AST | None, context: Context) -> None:
        """timeit and the like run a text as code: a function of the notebook's (or a lambda) is honest
        use; a constant text is flagged for review, at no cost (the scan does not read inside it);
        anything else, a text computed at run time, costs as exec does."""
        if code is None or isinstance(code, (ast.Lambda, ast.Attribute)) or (
                isinstance(code, ast.Name) and code.id in self.defined.first):
            return
        if isinstance(code, ast.Constant) and isinstance(code.value, str):
            self.hit(node, "none", f"gives {path} code as a text, which the scan does not read: look at it", context)
        else:
            self.hit(node, "shared", f"runs code from a text ({path}), which this scan cannot see", context)

    def display_reader(self, func: ast.AST, context: Context) -> bool:
        """Whether ``func`` is one of IPython.display's classes that read the file a string names."""
        if isinstance(func, ast.Name):
            path = None if self.shadowed(func.id, context) else self.modules.get(func.id)
        else:
            path = self.module_of(func)
        return path is not None and path.rpartition(".")[0] == DISPLAY_MODULE and path.rpartition(".")[2] in DISPLAY_READERS

    def display_argument(self, node: ast.Call, arg: ast.AST, context: Context) -> None:
        """The text (or file name) given to an IPython.display class: a name with a ``/`` in its
        constant parts is read as a file's and checked as ``open`` checks it; text without one (TeX's
        backslashes included) is at most a file of the student's own folder; a text computed at run time
        is flagged for review and costs nothing (under the sandbox the kernel reads no file of the course)."""
        folded = fold(arg)
        pieces = [folded] if isinstance(folded, str) else constant_pieces(arg)
        if pieces is None or (not any(p.strip() for p in pieces) and not isinstance(folded, str)):
            self.hit(node, "none", "gives IPython.display a text computed at run time, which it reads as a file's "
                                   "name if a file of that name exists: look at what the cell showed", context)
        elif any("/" in piece or piece.startswith("~") for piece in pieces):
            self.file_access(node, arg, False, context)

    def dynamic_attribute(self, node: ast.Call, name: str, context: Context) -> None:
        target, attr = node.args[0], fold(node.args[1])
        store = name in ("setattr", "delattr")
        # getattr(np, name) for name in ("mean", "median"): each name as if written out
        names = [attr] if isinstance(attr, str) else loop_constants(node.args[1], context.top)
        if names is not None and not isinstance(attr, str) and not all(
                _plain_attribute_name(ast.Constant(choice)) for choice in names):
            names = None  # a choice that names a module or a special attribute: as a computed name
        for attr in names or ():
            if attr in REFERENCE_ATTRIBUTES:
                self.hit(node, "reference", f"uses {name}(..., {attr!r}), which reaches the hidden tests' variables, "
                                            "their code or the reference's files", context)
            elif attr in SHARED_ATTRIBUTES or attr == "__dict__":
                self.hit(node, "shared", f"uses {name}(..., {attr!r}) to tamper with attributes", context)
            elif store and attr in FORBIDDEN_DUNDERS | {"__class__"}:
                self.hit(node, "none", f"sets {attr} with {name}: {OBJECTS_ARE_NOT_SENT}", context)
            path = self.module_of(target)
            if path is not None:
                self.check_path(f"{path}.{attr}", node, context, store=store)
        if names is not None:
            return
        if self.module_of(target) is not None or isinstance(target, ast.Call) or (
                isinstance(target, ast.Name) and not self.shadowed(target.id, context)
                and (target.id in BUILTIN_NAMES or target.id in self.builtin_aliases)):
            # a module, a call's result, or a builtin (print.__self__ is the builtins module)
            kind = "shared" if store else "reference"
            self.hit(node, kind, f"uses {name} with a computed attribute name on {self.module_of(target) or 'an object'}",
                     context)
        else:  # the student's own object, as in getattr(result, name) over a list of names: for review, no cost
            self.hit(node, "none", f"uses {name} with a computed attribute name on the notebook's own object "
                                   f"{ast.unparse(target)[:40]}: look at which attributes it reaches", context)

    def file_path_seen(self, arg: ast.AST, node: ast.AST, context: Context) -> None:
        folded = fold(arg)
        if isinstance(folded, str):
            why = path_problem(folded, writing=False)
            if why:
                self.hit(node, "reference", f"builds the path {folded!r}, which {why}", context)

    def file_access(self, node, arg, writes, context, unknown_ok: bool = False, resolving: bool = True) -> None:
        """A file access with path expression ``arg``; ``writes`` True, False, or None (unknown). A name
        bound once to a value stands for the value; a parameter of the notebook's own function, for
        what every call of it passes (``resolving``: look them up)."""
        choices = self.parameter_choices(arg, context) if resolving else None
        if choices is not None:
            for choice in choices:
                self.file_access(node, choice, writes, context, unknown_ok, resolving=False)
            return
        if arg is not None:
            arg = substitute(arg, self.defined.values)
        writing = writes is not False
        kind = "shared" if writing else "reference"
        verb = "writes" if writes else ("reads" if writes is False else "opens")
        if arg is None:
            if not unknown_ok:
                self.hit(node, kind, f"{verb} a file whose name this scan cannot see", context)
            return
        folded = fold(arg)
        if isinstance(folded, str):
            why = path_problem(folded, writing)
            if why:
                self.hit(node, kind, f"{verb} {folded!r}, which {why}", context)
            return
        pieces = constant_pieces(arg)
        if pieces is not None and pieces:
            for piece in pieces:
                why = path_problem(piece, writing, fragment=True)
                if why:
                    self.hit(node, kind, f"{verb} a file named from {piece!r}, which {why}", context)
                    return
            if any(p.strip() for p in pieces):
                return  # a name like f"fig_{i}.png" in the working folder
        if isinstance(arg, ast.Call) and self.module_of(arg.func) in IN_MEMORY_FILES:
            return  # np.loadtxt(io.StringIO(text)): text held in memory, no file's name
        self.hit(node, kind, f"{verb} a file whose name is computed at run time", context)


    def parameter_choices(self, arg: ast.AST | None, context: Context) -> list[ast.AST] | None:
        """For a parameter of the module-level function being scanned, not bound again in it, what
        the notebook's calls of the function pass for it (syntax.argument_choices); else None."""
        function = context.top
        if not (isinstance(arg, ast.Name) and isinstance(function, ast.FunctionDef) and len(context.params) == 1
                and arg.id in {a.arg for a in (*function.args.posonlyargs, *function.args.args, *function.args.kwonlyargs)}):
            return None
        if any(isinstance(n, ast.Name) and n.id == arg.id and not isinstance(n.ctx, ast.Load) for n in ast.walk(function)):
            return None
        return argument_choices(list(self.defined.trees), function.name, arg.id)

    def magic(self, node: ast.Call, context: Context) -> bool:
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
                    self.nested(strip_magic_options(line), node, context)
                return True
            self.hit(node, "shared", f"runs the IPython magic %{name} {line}".rstrip(), context)
            return True
        body = args[2] if len(args) > 2 else ""
        if name in SAFE_CELL_MAGICS:
            if name in CODE_MAGICS:
                self.nested(strip_magic_options(line), node, context)
            self.nested(body, node, context)
            return True
        self.hit(node, "shared", f"runs the IPython cell magic %%{name}", context)
        return True

    def nested(self, code: str, node: ast.AST, context: Context) -> None:
        tree = copy.deepcopy(parse(code))
        if tree is None:
            return
        for stmt in tree.body:
            for child in ast.walk(stmt):
                if hasattr(child, "lineno"):
                    child.lineno = getattr(node, "lineno", 1)
            self.visit(stmt, context)


def _plain_attribute_name(arg: ast.AST) -> bool:
    """Whether ``arg`` is a constant attribute name (dotted or not) with no special part, and no part
    that names a module or a module's dangerous attribute: operator.attrgetter("score"), not
    operator.attrgetter("os.system")."""
    dangerous = REFERENCE_ATTRIBUTES | REEXPORTED_MODULES | KNOWN_MODULE_NAMES | {
        name for names in (*MODULE_REFERENCE.values(), *MODULE_SHARED.values()) for name in names}
    return (isinstance(arg, ast.Constant) and isinstance(arg.value, str) and all(
        part.isidentifier() and not part.startswith("_") and part not in dangerous for part in arg.value.split(".")))

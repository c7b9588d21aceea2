"""Reading a cell's syntax tree for the scan: parsing a cell as IPython runs it, the names a
statement binds, constant folding of strings, and the shapes of calls that open files."""

from __future__ import annotations

import ast
import copy
import functools
import re


@functools.lru_cache(maxsize=4096)
def parse(source: str) -> ast.Module | None:
    """The syntax tree of a cell as IPython runs it (magics become get_ipython() calls), or None.

    Cached: callers must not modify the tree.
    """
    try:
        code = transformer().transform_cell(source)
    except Exception:
        code = source
    for attempt in (code, "\n".join(line for line in source.splitlines() if not line.lstrip().startswith(("%", "!")))):
        try:
            return ast.parse(attempt)
        except (SyntaxError, ValueError):
            continue
    return None


@functools.lru_cache(maxsize=1)
def transformer():
    from IPython.core.inputtransformer2 import TransformerManager

    return TransformerManager()


def bound_names(stmt: ast.AST | None) -> list[str]:
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
        names += target_names(target)
    if isinstance(stmt, (ast.If, ast.Try, ast.While, ast.With, ast.For)):
        for child in ast.iter_child_nodes(stmt):
            if isinstance(child, ast.stmt):
                names += bound_names(child)
        for handler in getattr(stmt, "handlers", []):
            for child in handler.body:
                names += bound_names(child)
    return names


def local_names(definition: ast.AST) -> set[str]:
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


def target_names(target: ast.AST) -> list[str]:
    """The names an assignment target binds (``a, (b, *c) = ...``); none for attributes and items."""
    if isinstance(target, ast.Name):
        return [target.id]
    if isinstance(target, (ast.Tuple, ast.List)):
        return [name for element in target.elts for name in target_names(element)]
    if isinstance(target, ast.Starred):
        return target_names(target.value)
    return []


def loop_constants(node: ast.AST, top: ast.AST | None) -> list[str] | None:
    """The strings a name can hold when its only binding in the statement ``top`` is as the loop
    variable over a literal of constant strings (``for name in ("mean", "median"):`` or the same in a
    comprehension), or None: any other binding of the name, or another loop, and it can hold anything."""
    if not isinstance(node, ast.Name) or top is None:
        return None
    choices, bindings = None, 0
    for inner in ast.walk(top):
        if isinstance(inner, (ast.For, ast.AsyncFor, ast.comprehension)) and isinstance(inner.target, ast.Name) \
                and inner.target.id == node.id:
            values = [fold(e) for e in inner.iter.elts] if isinstance(inner.iter, (ast.List, ast.Tuple, ast.Set)) else [None]
            choices = values if all(isinstance(v, str) for v in values) else None
        if isinstance(inner, ast.Name) and inner.id == node.id and isinstance(inner.ctx, (ast.Store, ast.Del)):
            bindings += 1
        elif isinstance(inner, ast.arg) and inner.arg == node.id:
            bindings += 2
    return choices if bindings == 1 else None


def substitute(node: ast.AST, values: dict[str, ast.AST], depth: int = 4) -> ast.AST:
    """A copy of ``node`` in which each name that ``values`` holds is replaced by its value (itself with
    its names replaced, ``depth`` times at most): ``out = "fig.png"`` makes ``savefig(out)`` read as
    ``savefig("fig.png")``."""
    if depth == 0 or not values:
        return node

    class Replace(ast.NodeTransformer):
        def visit_Name(self, name: ast.Name) -> ast.AST:
            if isinstance(name.ctx, ast.Load) and name.id in values:
                return substitute(values[name.id], values, depth - 1)
            return name

    return Replace().visit(copy.deepcopy(node))


def single_values(trees: list[ast.Module]) -> dict[str, ast.AST]:
    """The names that the trees bind exactly once in all, by a plain assignment ``name = value``:
    name -> value. A name bound twice anywhere (again, as a parameter, a loop variable, an import, a
    definition, ``global``) is left out, whatever scope each binding is in."""
    bindings: dict[str, int] = {}
    values: dict[str, ast.AST] = {}
    for tree in trees:
        for node in ast.walk(tree):
            names = []
            if isinstance(node, ast.Name) and isinstance(node.ctx, (ast.Store, ast.Del)):
                names = [node.id]
            elif isinstance(node, ast.arg):
                names = [node.arg]
            elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                names = [node.name]
            elif isinstance(node, (ast.Import, ast.ImportFrom)):
                names = [(a.asname or a.name).split(".")[0] for a in node.names]
            elif isinstance(node, (ast.Global, ast.Nonlocal)):
                names = list(node.names) * 2
            for name in names:
                bindings[name] = bindings.get(name, 0) + 1
            if isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name):
                values[node.targets[0].id] = node.value
    return {name: value for name, value in values.items() if bindings.get(name) == 1}


def argument_choices(trees: list[ast.Module], function: str, parameter: str) -> list[ast.AST] | None:
    """What the notebook passes as ``parameter`` of its module-level function ``function``: the
    argument of every call ``function(...)`` (by position or keyword, or the default), or None when
    the function is used otherwise than called by its name, or a call passes ``*args`` or ``**kwargs``."""
    definition = next((node for tree in trees for node in tree.body
                       if isinstance(node, ast.FunctionDef) and node.name == function), None)
    if definition is None:
        return None
    positional = [a.arg for a in definition.args.posonlyargs + definition.args.args]
    defaults = dict(zip(positional[len(positional) - len(definition.args.defaults):], definition.args.defaults))
    defaults |= {a.arg: d for a, d in zip(definition.args.kwonlyargs, definition.args.kw_defaults) if d is not None}
    index = positional.index(parameter) if parameter in positional else None
    calls, choices = set(), []
    for tree in trees:
        for node in ast.walk(tree):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == function:
                calls.add(id(node.func))
                if any(isinstance(a, ast.Starred) for a in node.args) or any(k.arg is None for k in node.keywords):
                    return None
                given = [k.value for k in node.keywords if k.arg == parameter]
                if index is not None and index < len(node.args):
                    given.append(node.args[index])
                choice = given[0] if given else defaults.get(parameter)
                if choice is None:
                    return None
                choices.append(choice)
    used = [node for tree in trees for node in ast.walk(tree)
            if isinstance(node, ast.Name) and node.id == function and id(node) not in calls]
    return None if used else choices


def fold(node: ast.AST):
    """The string value of a constant string expression, or None."""
    if isinstance(node, ast.Constant):
        return node.value if isinstance(node.value, str) else None
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Div)):
        left, right = fold(node.left), fold(node.right)
        if isinstance(left, str) and isinstance(right, str):
            return left + ("/" if isinstance(node.op, ast.Div) else "") + right
        return None
    if isinstance(node, ast.JoinedStr):
        parts = [fold(v) if not isinstance(v, ast.FormattedValue) else fold(v.value) for v in node.values]
        return "".join(parts) if all(isinstance(p, str) for p in parts) else None
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
        if node.func.attr == "join" and len(node.args) == 1 and isinstance(node.args[0], (ast.List, ast.Tuple)):
            sep = fold(node.func.value)
            if isinstance(node.func.value, ast.Attribute) and node.func.value.attr == "path":
                sep = None
            items = [fold(e) for e in node.args[0].elts]
            if isinstance(sep, str) and all(isinstance(i, str) for i in items):
                return sep.join(items)
        if node.func.attr == "join" and isinstance(node.func.value, ast.Attribute) and node.func.value.attr == "path":
            items = [fold(a) for a in node.args]
            if items and all(isinstance(i, str) for i in items):
                return "/".join(items)
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in ("str", "Path") and node.args:
        return fold(node.args[0])
    return None


def constant_pieces(node: ast.AST) -> list[str] | None:
    """The constant string pieces of an f-string, a sum of strings or os.path.join, or None."""
    if isinstance(node, ast.JoinedStr):
        return [v.value for v in node.values if isinstance(v, ast.Constant) and isinstance(v.value, str)]
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Div)):
        pieces = []
        for side in (node.left, node.right):
            folded = fold(side)
            if isinstance(folded, str):
                pieces.append(folded)
            else:
                inner = constant_pieces(side)
                if inner:
                    pieces += inner
        return pieces
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "join":
        return [f for f in (fold(a) for a in node.args) if isinstance(f, str)] or None
    return None


def first_arg(node: ast.Call, keyword: str) -> ast.AST | None:
    if node.args:
        return node.args[0]
    for kw in node.keywords:
        if kw.arg == keyword:
            return kw.value
    return None


def open_writes(node: ast.Call, position: int) -> bool | None:
    """Whether an open(...) call writes: True, False, or None if its mode is not a constant."""
    mode = node.args[position] if len(node.args) > position else next(
        (kw.value for kw in node.keywords if kw.arg == "mode"), None)
    if mode is None:
        return False
    folded = fold(mode)
    if not isinstance(folded, str):
        return None
    return any(c in folded for c in "wax+")


def path_constructor_arg(node: ast.AST) -> ast.AST | None:
    """For ``Path(x)`` (or ``pathlib.Path(x)``, ``Path(x) / y``), the path expression; else None."""
    if isinstance(node, ast.Call):
        func = node.func
        name = func.id if isinstance(func, ast.Name) else (func.attr if isinstance(func, ast.Attribute) else "")
        if name in ("Path", "PurePath", "PosixPath") and node.args:
            return node.args[0] if len(node.args) == 1 else ast.BinOp(node.args[0], ast.Div(), node.args[1])
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Div):
        base = path_constructor_arg(node.left)
        if base is not None:
            return ast.BinOp(base, ast.Div(), node.right)
    return None


def catches_everything(handler: ast.ExceptHandler) -> bool:
    kinds = handler.type
    if kinds is None:
        return True
    names = kinds.elts if isinstance(kinds, ast.Tuple) else [kinds]
    return any(isinstance(n, ast.Name) and n.id in ("Exception", "BaseException") for n in names)


def does_nothing(stmt: ast.stmt) -> bool:
    return isinstance(stmt, (ast.Pass, ast.Continue)) or (isinstance(stmt, ast.Expr) and isinstance(stmt.value, ast.Constant))


def strip_magic_options(line: str) -> str:
    """The statement of a %time/%timeit line, without its options (-n 10 -r 3 -q ...)."""
    return re.sub(r"^(\s*-[A-Za-z](\s+(?!-)\S+)?)*\s*", "", line) if line.lstrip().startswith("-") else line

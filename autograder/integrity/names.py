"""The scan's rules for imports, names, attributes and stores into modules."""

from __future__ import annotations

import ast

from autograder.integrity.rules import (
    ALLOWED_MODULE_STORES,
    DUNDER_GLOBALS,
    FORBIDDEN_DUNDERS,
    OBJECTS_ARE_NOT_SENT,
    HIDDEN_PACKAGES,
    IMPORT_MACHINERY,
    MODULE_REFERENCE,
    MODULE_REVIEW,
    MODULE_SHARED,
    REFERENCE_ATTRIBUTES,
    SHARED_ATTRIBUTES,
    SHELL_PACKAGES,
    DISPLAY_MODULE,
    DISPLAY_NAMES,
    SYSTEM_PACKAGES,
    SYSTEM_SUBMODULES,
)
from autograder.integrity.walker import Context, Walker


class NameRules(Walker):
    """Imports, names, attributes and subscripts."""

    def visit_Import(self, node: ast.Import, context: Context):
        for alias in node.names:
            if alias.asname is None and alias.name.startswith(DISPLAY_MODULE):
                self.check_module("IPython", node, context)  # binds IPython, the whole of it
            else:
                self.check_module(alias.name, node, context)

    def visit_ImportFrom(self, node: ast.ImportFrom, context: Context):
        if node.level:
            self.hit(node, "reference", "uses a relative import, which reaches packages beside the notebook", context)
            return
        module = node.module or ""
        if module == "IPython" and all(alias.name == "display" for alias in node.names):
            module = DISPLAY_MODULE  # from IPython import display
        elif module == DISPLAY_MODULE:
            for alias in node.names:
                if alias.name not in DISPLAY_NAMES:
                    self.hit(node, "shared", f"imports {alias.name} from IPython.display, which is not rich output "
                                             "a lab needs", context)
            return
        if self.check_module(module, node, context):
            return
        for alias in node.names:
            if alias.name != "*":
                self.check_path(f"{module}.{alias.name}", node, context, store=False)

    def check_module(self, module: str, node: ast.AST, context: Context) -> bool:
        top = module.split(".")[0]
        if module == DISPLAY_MODULE:
            return True  # rich output only: it shows in the student's own page and decides no score
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


    def visit_Name(self, node: ast.Name, context: Context):
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

    def visit_Attribute(self, node: ast.Attribute, context: Context):
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

    def attribute_name(self, node, attr: str, store: bool, module: bool, context: Context) -> None:
        if attr in REFERENCE_ATTRIBUTES:
            self.hit(node, "reference", f"uses .{attr}, which reaches the hidden tests' variables, their code or "
                                        "the reference's files", context)
        elif attr in SHARED_ATTRIBUTES:
            self.hit(node, "shared", f"uses .{attr}, which tampers with other objects' attributes", context)
        elif attr == "__dict__":
            if module or not isinstance(node.value, ast.Name):
                self.hit(node, "shared" if store else "reference", "reaches into a module's __dict__", context)
        elif store and (attr in FORBIDDEN_DUNDERS or attr == "__class__"):
            self.hit(node, "none", f"sets {attr} on an object: {OBJECTS_ARE_NOT_SENT}", context)

    def visit_Subscript(self, node: ast.Subscript, context: Context):
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

    def check_path(self, path: str, node: ast.AST, context: Context, store: bool) -> None:
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
        if path.startswith(DISPLAY_MODULE + ".") and parts[2] not in DISPLAY_NAMES:
            self.hit(node, "shared", f"uses {path}, which is not rich output a lab needs", context)
            return
        for kind, table, why in (
                ("reference", MODULE_REFERENCE, "a route to the hidden reference or to the hidden tests' variables"),
                ("shared", MODULE_SHARED, "which tampers with the kernel or the machine"),
                ("none", MODULE_REVIEW, "which can run any code packed into what it loads: look at where that comes from")):
            if len(parts) > 1 and parts[1] in table.get(top, ()):
                self.hit(node, kind, f"uses {top}.{parts[1]}, {why}", context)
                return
        if top == "ctypes" and len(parts) > 1:  # reached through another module (np.ctypeslib.ctypes.pythonapi)
            self.hit(node, "shared", f"uses {path}, which calls into the C library and Python's own C API", context)
            return
        if top != "sys" and "sys" in parts[1:-1] and parts[parts.index("sys", 1) + 1] in MODULE_REFERENCE["sys"]:
            self.hit(node, "reference", f"uses {path}, sys reached through another module", context)
            return
        if top == "os" and len(parts) > 1 and parts[1] == "environ" and len(parts) > 2 and parts[2] in (
                "update", "setdefault", "pop", "clear", "__setitem__"):
            self.hit(node, "shared", "changes environment variables", context)

"""The grading kernel's half of the cheating defences: an audit hook and a snapshot of the originals.

``autograder.integrity.INTEGRITY_SETUP`` calls :func:`install` in the grading kernel before any
student cell runs. It

1. imports the lab's hidden tests (so the reference, the check helpers and NumPy are loaded
   before the student can touch them) and snapshots what grading relies on: every function and
   class of ``numpy``, ``scipy``, ``matplotlib``, ``course``, ``autograder`` and ``solutions``
   (with their code objects), ``builtins``, the hooks in ``sys``, and IPython's shell and kernel
   (methods, input and AST transformers, event callbacks, custom exception handlers);
2. adds a ``sys.addaudithook`` hook. Audit hooks cannot be removed, and the hook blocks any hook
   added after it. It watches what code from the student's cells does, wherever it runs
   (including inside a hidden test that calls the student's function): imports of ``solutions``
   and ``autograder``, reads of the reference's files, writes outside the submission's folder
   (the gradebook, other students' folders, files grading reads), shell commands,
   ``exec``/``compile``, frame walking, ``gc`` searches, tracing, and swapping the code of a
   library function. The worst of these are refused (the operation raises ``PermissionError``);
   all are recorded. Plain attribute assignments (``np.allclose = ...``) raise no audit event:
   the snapshot comparison finds those.

The snapshot and the findings live only in the hook's closure: no module attribute or notebook
name leads to them (``gc`` searches and frame walks from student code are what could, and the
hook watches both). ``RUNTIME_PROBE`` asks for the report by raising the audit event
``REPORT_EVENT`` with an empty list; the hook compares the kernel with the snapshot and puts one
JSON string in the list: a header, then one ``{"reason": ..., "blanks": [...] or null}`` per
finding, cumulative since the start.

A finding's ``blanks`` names the blanks whose student code did it (from the call stack, or the
functions the offending cell defines); ``null`` means every blank (shared machinery tampered
with, or code that cannot be tied to a blank).

This module imports only the standard library at import time; it is not student-facing.
"""

from __future__ import annotations

import ast
import json
import linecache
import os
import site
import sys
import sysconfig
import threading
import types
from pathlib import Path

REPORT_EVENT = "estimation-lab-kit.integrity.report"
HEADER = {"monitor": "estimation-lab-kit integrity monitor", "version": 1}

ROOT = Path(__file__).resolve().parent.parent
"""The course root: ``course``, ``autograder`` and ``solutions`` live here."""

PROTECTED_PACKAGES = ("numpy", "scipy", "matplotlib", "course", "autograder", "solutions", "math", "cmath",
                      "operator", "functools", "json")
"""Top-level packages whose functions, classes and submodules are snapshotted."""
HIDDEN_PACKAGES = ("solutions", "autograder")
"""Packages student code must not import or read."""
COURSE_CODE_DIRS = ("course", "autograder", "solutions")

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

IPYTHON_BUILTINS = frozenset({"_", "__", "___", "get_ipython", "display", "exit", "quit", "__IPYTHON__", "input", "raw_input",
                              "copyright", "credits", "license", "help", "dreload", "__IPYTHON__active"})
"""Names IPython itself puts into and takes out of ``builtins``."""

SHELL_CRITICAL = frozenset({
    "showtraceback", "_showtraceback", "showsyntaxerror", "showindentationerror", "run_cell",
    "run_cell_async", "_run_cell", "run_ast_nodes", "run_code", "transform_cell", "transform_ast",
    "should_run_async", "user_expressions", "ex", "ev", "excepthook", "set_custom_exc", "CustomTB",
    "custom_exceptions", "InteractiveTB", "SyntaxTB", "compile", "displayhook", "display_pub",
    "display_trap", "builtin_trap", "events", "input_transformer_manager", "ast_transformers",
    "input_transformers_post", "user_ns", "user_global_ns", "user_module", "kernel",
    "get_exception_only", "_get_exc_info", "run_line_magic", "run_cell_magic", "system", "getoutput",
    "do_execute", "execute_request", "send_response", "shell_handlers", "control_handlers", "session",
    "send", "iopub_socket", "user_expressions",
})
"""Attributes of the shell, kernel and session that must stay exactly as they were."""

WRITE_EVENTS = {
    # event: indices of the path arguments it writes
    "os.remove": (0,), "os.rename": (0, 1), "os.rmdir": (0,), "os.mkdir": (0,), "os.symlink": (1,),
    "os.link": (1,), "os.chmod": (0,), "os.chown": (0,), "os.truncate": (0,), "os.utime": (0,),
    "shutil.copyfile": (1,), "shutil.copymode": (1,), "shutil.copystat": (1,), "shutil.move": (0, 1),
    "shutil.rmtree": (0,), "shutil.chown": (0,), "sqlite3.connect": (0,),
}
SPAWN_EVENTS = frozenset({"subprocess.Popen", "os.system", "os.exec", "os.spawn", "os.posix_spawn", "os.fork",
                          "os.forkpty", "pty.spawn", "os.startfile", "os.kill", "os.killpg"})
FRAME_EVENTS = frozenset({"sys._getframe", "sys._current_frames"})
GC_EVENTS = frozenset({"gc.get_objects", "gc.get_referrers", "gc.get_referents"})
TRACE_EVENTS = frozenset({"sys.settrace", "sys.setprofile"})
WATCHED = (frozenset({"import", "open", "exec", "compile", "object.__setattr__", "object.__delattr__",
                      "object.__getattr__", "sys.addaudithook", "os.chdir", "ctypes.dlopen",
                      "ctypes.dlsym", "ctypes.cdata", "ctypes.addressof", "ctypes.call_function",
                      "ctypes.string_at", "ctypes.wstring_at", "_thread.start_new_thread", REPORT_EVENT})
           | SPAWN_EVENTS | FRAME_EVENTS | GC_EVENTS | TRACE_EVENTS | frozenset(WRITE_EVENTS))
FRAME_ATTRIBUTES = frozenset({"tb_frame", "gi_frame", "cr_frame", "ag_frame"})
BENIGN_COMMANDS = frozenset({"pip", "pip3", "conda", "mamba", "ls", "pwd", "echo", "which", "nvidia-smi", "date",
                             "whoami", "uname", "hostname"})
"""Shell commands an honest student leaves in a notebook. They are refused during grading like any
other, and flagged, but cost no points."""


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


def install() -> None:
    """Snapshot the originals and add the audit hook (see the module docstring). Idempotent.

    Nothing that leads to the monitor's state is kept outside the hook's closure.
    """
    global _installed
    if _installed:
        return
    _installed = True
    sys.addaudithook(_Monitor().make_hook())


_installed = False


def _is_under(path: str, folder: str) -> bool:
    return path == folder or path.startswith(folder.rstrip(os.sep) + os.sep)


def _quote(text: str) -> str:
    """A JSON string literal, without going through ``json`` (which student code could patch)."""
    out = []
    for ch in text:
        if ch == '"' or ch == "\\":
            out.append("\\" + ch)
        elif ord(ch) < 0x20:
            out.append("\\u%04x" % ord(ch))
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _function_of(obj):
    """The Python function behind a function, a method or a NumPy dispatcher, or None."""
    for _ in range(4):
        if isinstance(obj, types.FunctionType):
            return obj
        if isinstance(obj, types.MethodType):
            obj = obj.__func__
            continue
        implementation = getattr(type(obj), "_implementation", None) and getattr(obj, "_implementation", None)
        if isinstance(implementation, types.FunctionType):
            return implementation
        return None
    return None


def _fingerprint(value):
    """What must stay identical for a snapshotted value: the object, and its code if it has any."""
    function = _function_of(value)
    if function is None:
        return (value, None, None, None, None)
    return (value, function, function.__code__, function.__defaults__, function.__kwdefaults__)


def _changed(value, fingerprint) -> bool:
    """Whether ``value`` differs from the snapshotted ``fingerprint``, or had its code swapped."""
    if value is not fingerprint[0]:
        return True
    function = fingerprint[1]
    return function is not None and (function.__code__ is not fingerprint[2] or function.__defaults__
                                     is not fingerprint[3] or function.__kwdefaults__ is not fingerprint[4])


class _Monitor:
    """State of the monitor. Only the hook's closure refers to the instance."""

    def __init__(self):
        self.guard = threading.local()
        self.findings: dict[str, object] = {}  # reason -> tuple of blanks, or None
        self.cwd = os.path.realpath(os.getcwd())
        cwd = Path(self.cwd)
        self.course_dir = (str(cwd.parents[2]) if len(cwd.parents) > 2
                           and cwd.parents[1].name in ("submitted", "autograded") else None)
        self.root = os.path.realpath(ROOT)
        self.code_dirs = tuple(os.path.join(self.root, d) for d in COURSE_CODE_DIRS)
        self.lib_dirs = self._library_dirs()
        self.tempdir = os.path.realpath(__import__("tempfile").gettempdir())
        self.kind_cache: dict[str, str] = {}
        self.labs = self._lab_ids()
        lab = cwd.name if cwd.name in self.labs else None
        self.lab_labs = [lab] if lab else self.labs
        self.blanks: set[str] = set()
        self.trusted_dumps: set[str] = set()
        self._read_notebooks()
        self._import_hidden_tests()
        self.shell = self._shell()
        self._snapshot()

    # -- what the lab is -------------------------------------------------------------------

    def _lab_ids(self) -> list[str]:
        source = os.path.join(self.root, "source")
        try:
            names = sorted(os.listdir(source))
        except OSError:
            return []
        return [n for n in names if os.path.isfile(os.path.join(source, n, n + ".ipynb"))]

    def _read_notebooks(self) -> None:
        """The blanks' names, and the syntax trees of the locked cells (the only trusted cells)."""
        try:
            from IPython.core.inputtransformer2 import TransformerManager
            transform = TransformerManager().transform_cell
        except Exception:  # pragma: no cover - IPython is always there in a kernel
            transform = None
        for lab in self.lab_labs:
            for folder in ("source", "release"):
                path = os.path.join(self.root, folder, lab, lab + ".ipynb")
                try:
                    with open(path, encoding="utf-8") as handle:
                        nb = json.load(handle)
                except (OSError, ValueError):
                    continue
                for cell in nb.get("cells", []):
                    if cell.get("cell_type") != "code":
                        continue
                    meta = cell.get("metadata", {}).get("nbgrader", {})
                    source = cell.get("source", "")
                    source = "".join(source) if isinstance(source, list) else source
                    if meta.get("solution"):
                        if not meta.get("grade"):
                            self.blanks.update(_defined_names(source))
                        continue
                    for text in {source, transform(source) if transform else source}:
                        dump = _dump(text)
                        if dump is not None:
                            self.trusted_dumps.add(dump)

    def _import_hidden_tests(self) -> None:
        import importlib

        for module in ("numpy", "numpy.testing", "numpy.linalg", "course.checks"):
            try:
                importlib.import_module(module)
            except Exception:
                pass
        for lab in self.lab_labs:
            try:
                importlib.import_module("autograder.hidden_tests." + lab.replace("-", "_"))
            except Exception:
                pass

    @staticmethod
    def _shell():
        ipython = sys.modules.get("IPython")
        try:
            return ipython.get_ipython() if ipython else None
        except Exception:
            return None

    def _library_dirs(self) -> tuple[str, ...]:
        """The standard library and site-packages folders of this Python and its base."""
        dirs = set()
        for scheme_vars in (None, {"base": sys.base_prefix, "platbase": sys.base_exec_prefix}):
            paths = sysconfig.get_paths(vars=scheme_vars)
            dirs.update(paths[key] for key in ("stdlib", "platstdlib", "purelib", "platlib"))
        try:
            dirs.update(site.getsitepackages())
            dirs.add(site.getusersitepackages())
        except Exception:
            pass
        for name in ("numpy", "IPython", "ipykernel", "os"):
            module = sys.modules.get(name)
            file = getattr(module, "__file__", None)
            if file:
                dirs.add(os.path.dirname(os.path.dirname(os.path.realpath(file))))
        real = {os.path.realpath(d) for d in dirs if d}
        # A folder that holds the course or the submission is not library code.
        return tuple(sorted(d for d in real if not _is_under(self.root, d) and not _is_under(self.cwd, d)))

    # -- where code comes from ---------------------------------------------------------------

    def file_kind(self, filename: str) -> str:
        """'lib', 'course', 'trusted' (a locked notebook cell), 'skip' (generated code) or 'student'."""
        kind = self.kind_cache.get(filename)
        if kind is not None:
            return kind
        if filename.startswith("<frozen") or filename in ("<string>", "<unknown>"):
            kind = "skip" if filename in ("<string>", "<unknown>") else "lib"
        else:
            real = os.path.realpath(filename) if os.path.isabs(filename) else filename
            if any(_is_under(real, d) for d in self.code_dirs):
                kind = "course"
            elif any(_is_under(real, d) for d in self.lib_dirs) and os.path.exists(real):
                kind = "lib"
            else:
                entry = linecache.cache.get(filename)
                source = "".join(entry[2]) if entry and len(entry) > 2 else None
                kind = "trusted" if source is not None and _dump(source) in self.trusted_dumps else "student"
        self.kind_cache[filename] = kind
        return kind

    def origin(self, obj) -> str:
        """'lib', 'course' or 'student': where a callable or class was defined."""
        function = _function_of(obj)
        if function is not None:
            return self._function_origin(function)
        if isinstance(obj, _C_CALLABLES):
            return "lib"  # code written in C cannot come from a notebook cell
        cls = obj if isinstance(obj, type) else type(obj)
        try:
            members = list(vars(cls).values())
        except TypeError:
            members = []
        for member in members:
            if isinstance(member, (classmethod, staticmethod)):
                member = member.__func__
            elif isinstance(member, property):
                member = member.fget
            function = _function_of(member)
            if function is not None and self._function_origin(function) == "student":
                return "student"
        module = sys.modules.get(getattr(cls, "__module__", "") or "")
        file = getattr(module, "__file__", None)
        if module is not None and module is sys.modules.get("__main__"):
            return "student"
        if file is None:
            return "lib"  # no Python code from a notebook cell in it (checked above): a C type
        kind = self.file_kind(file)
        return "student" if kind in ("student", "skip") else ("lib" if kind == "trusted" else kind)

    def _function_origin(self, function) -> str:
        kind = self.file_kind(function.__code__.co_filename)
        if kind == "skip":  # generated code (dataclasses, namedtuple, exec): judge by its module
            module = sys.modules.get(getattr(function, "__module__", None) or "")
            file = getattr(module, "__file__", None)
            if module is None or module is sys.modules.get("__main__") or file is None:
                return "student"
            kind = self.file_kind(file)
        return "student" if kind in ("student", "skip") else ("lib" if kind == "trusted" else kind)

    def student_frames(self, frame, passthrough=(), direct=False):
        """The student frames responsible for an event raised in ``frame``, innermost first.

        ``direct``: only the first frame that is not in a ``passthrough`` module decides (exec,
        setattr, frame walking, gc). Otherwise library frames are skipped and the first
        non-library frame decides (imports, file access, processes). Either way, if that frame is
        student code, every student frame on the stack is returned; else none.
        """
        f = frame
        deciding = None
        while f is not None:
            kind = self.file_kind(f.f_code.co_filename)
            name = f.f_globals.get("__name__", "") if kind == "lib" else ""
            if kind == "skip" or (kind == "lib" and (not direct or (name or "").split(".")[0] in passthrough)):
                f = f.f_back
                continue
            deciding = kind
            break
        if deciding != "student":
            return []
        frames = []
        while f is not None:
            if self.file_kind(f.f_code.co_filename) == "student":
                frames.append(f)
            f = f.f_back
        return frames

    def blanks_of(self, frames) -> tuple[str, ...] | None:
        """The blanks to charge for an event in these student frames (None: every blank)."""
        names = []
        for f in frames:  # the outermost function of each frame: predict.<locals>.Peek.__array__ -> predict
            name = getattr(f.f_code, "co_qualname", f.f_code.co_name).split(".")[0]
            if name in self.blanks and name not in names:
                names.append(name)
        if names:
            return tuple(names)
        for f in frames:
            if f.f_code.co_name == "<module>":
                entry = linecache.cache.get(f.f_code.co_filename)
                source = "".join(entry[2]) if entry and len(entry) > 2 else ""
                defined = [n for n in _defined_names(source) if n in self.blanks]
                if defined:
                    return tuple(defined)
        return None

    # -- files ---------------------------------------------------------------------------------

    def _resolve(self, path) -> str | None:
        if isinstance(path, int):
            return None
        try:
            path = os.fsdecode(os.fspath(path))
        except TypeError:
            return None
        return os.path.realpath(os.path.join(os.getcwd(), os.path.expanduser(path)))

    def protected_read(self, real: str) -> str | None:
        """Why reading ``real`` is not allowed, or None."""
        for d in ("solutions", "autograder", "source", ".git", "submitted", "autograded", "feedback"):
            if _is_under(real, os.path.join(self.root, d)):
                return f"reads {real}, part of the course's hidden material"
        if real.endswith((".db", ".sqlite", ".sqlite3")) or "gradebook" in os.path.basename(real):
            return f"opens the gradebook file {real}"
        if self.course_dir and _is_under(real, self.course_dir) and not _is_under(real, self.cwd):
            for d in ("submitted", "autograded", "feedback", "source", "release"):
                if _is_under(real, os.path.join(self.course_dir, d)):
                    return f"reads {real}, outside its own submission folder"
        return None

    def bad_write(self, real: str) -> str | None:
        """Why writing ``real`` is not allowed, or None."""
        read = self.protected_read(real)
        if read:
            return read.replace("reads", "writes to", 1).replace("opens", "writes to", 1)
        name = os.path.basename(real)
        if name == "timestamp.txt" or name.endswith((".py", ".pyc", ".pth", ".so", ".ipynb")):
            return f"writes {real}, a file that grading reads or imports"
        if _is_under(real, self.cwd):
            return None
        inside_course = (self.course_dir and _is_under(real, self.course_dir)) or _is_under(real, self.root)
        if not inside_course and _is_under(real, self.tempdir):
            return None
        for cache in (os.environ.get("MPLCONFIGDIR"), os.path.expanduser("~/.cache/matplotlib"),
                      os.path.expanduser("~/.config/matplotlib")):
            if cache and _is_under(real, os.path.realpath(cache)):
                return None
        return f"writes to {real}, outside its own submission folder"

    # -- the snapshot --------------------------------------------------------------------------

    def _snapshot(self) -> None:
        self.modules = {}
        self.classes = {}
        for name, module in list(sys.modules.items()):
            if isinstance(module, types.ModuleType) and name.split(".")[0] in PROTECTED_PACKAGES:
                self.modules[name] = (module, self._module_state(module))
                for value in list(vars(module).values()):
                    if isinstance(value, type) and getattr(value, "__module__", None) == name:
                        self.classes[value] = self._class_state(value)
        import builtins

        self.builtins_module = builtins
        self.builtins = dict(vars(builtins))
        self.missing, self.ipython_builtins = _MISSING, IPYTHON_BUILTINS
        own = globals()
        self.own_code = [
            (own, {k: (v, getattr(v, "__code__", None)) for k, v in own.items() if not k.startswith("__") and k != "_installed"}),
            (_Monitor.__dict__, {k: (v, getattr(v, "__code__", None)) for k, v in _Monitor.__dict__.items()}),
        ]
        self.sys_hooks = {name: getattr(sys, name, None) for name in (
            "excepthook", "displayhook", "breakpointhook", "unraisablehook", "stdout", "stderr", "stdin",
            "audit", "addaudithook", "_getframe", "settrace", "setprofile", "exc_info")}
        self.sys_lists = {name: list(getattr(sys, name)) for name in ("meta_path", "path_hooks", "path")}
        self.trace = (sys.gettrace(), sys.getprofile())
        self.objects = []  # (label, object, instance dict copy)
        self.lists = []  # (label, list object, copy)
        shell = self.shell
        if shell is None:
            self.user_ns = None
            return
        self.user_ns = shell.user_ns
        self.user_builtins = shell.user_ns.get("__builtins__")
        kernel = getattr(shell, "kernel", None)
        candidates = [("the IPython shell", shell), ("the kernel", kernel),
                      ("the kernel's session", getattr(kernel, "session", None))]
        for attr in ("displayhook", "display_pub", "compile", "InteractiveTB", "SyntaxTB", "events",
                     "input_transformer_manager", "builtin_trap", "display_trap", "history_manager",
                     "payload_manager", "display_formatter", "magics_manager"):
            candidates.append((f"the shell's {attr}", getattr(shell, attr, None)))
        for label, obj in candidates:
            if obj is None:
                continue
            self.objects.append((label, obj, _attributes(obj)))
            for cls in type(obj).__mro__:
                if cls.__module__ != "builtins" and cls not in self.classes:
                    self.classes[cls] = self._class_state(cls)
        lists = (
            ("IPython's input_transformers_cleanup",
             lambda: shell.input_transformer_manager.cleanup_transforms),
            ("IPython's line transforms", lambda: shell.input_transformer_manager.line_transforms),
            ("IPython's token transformers", lambda: shell.input_transformer_manager.token_transformers),
            ("IPython's input_transformers_post", lambda: shell.input_transformers_post),
            ("IPython's ast_transformers", lambda: shell.ast_transformers),
        )
        for label, getter in lists:
            seq = getter()
            self.lists.append((label, getter, seq, list(seq)))
        self.callbacks_dict = shell.events.callbacks
        self.callbacks = {event: list(callbacks) for event, callbacks in shell.events.callbacks.items()}
        self.handlers = {}
        for attr in ("shell_handlers", "control_handlers"):
            table = getattr(kernel, attr, None)
            if isinstance(table, dict):
                self.handlers[attr] = (table, dict(table))
        self.custom = (shell.custom_exceptions, shell.CustomTB)

    @staticmethod
    def _module_state(module) -> dict:
        state = {}
        for key, value in list(vars(module).items()):
            if callable(value) or isinstance(value, types.ModuleType):
                if isinstance(value, types.ModuleType) and key.startswith("_"):
                    continue
                state[key] = _fingerprint(value)
        return state

    @staticmethod
    def _class_state(cls) -> dict:
        try:
            items = list(vars(cls).items())
        except TypeError:
            return {}
        return {key: _fingerprint(value) for key, value in items
                if callable(value) or isinstance(value, (classmethod, staticmethod, property))}

    # -- the checks ----------------------------------------------------------------------------

    def add(self, reason: str, blanks) -> None:
        if reason not in self.findings:
            self.findings[reason] = blanks

    def state_findings(self) -> list[tuple[str, object]]:
        out: list[tuple[str, object]] = []
        seen_modules = set()
        for name, (module, state) in self.modules.items():
            seen_modules.add(name)
            current = sys.modules.get(name)
            if current is not module:
                out.append((f"The loaded module {name} was replaced or removed in sys.modules.", None))
            namespace = vars(module)
            lenient = name.split(".")[0] == "matplotlib"  # pyplot swaps its backend functions itself
            for key, before in state.items():
                value = namespace.get(key, _MISSING)
                if value is _MISSING:
                    out.append((f"{name}.{key} was deleted.", None))
                elif _changed(value, before) and not (lenient and self.origin(value) == "lib"):
                    out.append((f"{name}.{key} was replaced (monkeypatched).", None))
            for key, value in list(vars(module).items()):
                if key not in state and callable(value) and not isinstance(value, type) and self.origin(value) == "student":
                    out.append((f"{name}.{key} was set to a function defined in the notebook.", None))
        for name, module in list(sys.modules.items()):
            if name in seen_modules or not isinstance(name, str) or name.split(".")[0] not in PROTECTED_PACKAGES:
                continue
            if not isinstance(module, types.ModuleType):
                out.append((f"sys.modules[{name!r}] is not a module loaded from disk.", None))
                continue
            file = getattr(module, "__file__", None)
            kind = self.file_kind(os.path.realpath(file)) if file else ("lib" if name in sys.builtin_module_names else "student")
            if kind not in ("lib", "course"):
                out.append((f"sys.modules[{name!r}] holds a module that was not loaded from the course or the library.", None))
                continue
            for key, value in list(vars(module).items()):
                if callable(value) and not isinstance(value, type) and self.origin(value) == "student":
                    out.append((f"{name}.{key} was set to a function defined in the notebook.", None))
        for cls, state in self.classes.items():
            try:
                now = vars(cls)
            except TypeError:
                continue
            for key, before in state.items():
                value = now.get(key, _MISSING)
                if value is _MISSING:
                    out.append((f"{_qualified(cls)}.{key} was deleted.", None))
                elif _changed(value, before):
                    out.append((f"{_qualified(cls)}.{key} was replaced (monkeypatched).", None))
            for key in now.keys() - state.keys():
                value = now[key]
                if callable(value) and self.origin(value) == "student":
                    out.append((f"{_qualified(cls)}.{key} was added by the notebook (monkeypatched).", None))
        for name, before in self.sys_hooks.items():
            value = getattr(sys, name, None)
            if value is before or value == before:
                continue
            if name in ("excepthook", "displayhook") and (value is getattr(sys, "__" + name + "__") or _ipython_owned(value)):
                continue  # IPython swaps these around each cell
            out.append((f"sys.{name} was replaced.", None))
        for name, before in self.sys_lists.items():
            now = getattr(sys, name, [])
            added = [item for item in now if not any(item is b or (isinstance(item, str) and item == b) for b in before)]
            if name == "path":
                if added:
                    out.append((f"sys.path was edited: {added!r} added.", None))
            else:
                for item in added:
                    if self.origin(item) == "student":
                        out.append((f"sys.{name} has an import hook defined in the notebook.", None))
        if (sys.gettrace(), sys.getprofile()) != self.trace:
            out.append(("A trace or profile function was installed (sys.settrace or sys.setprofile).", None))
        out += self._shell_findings()
        out += self._class_dunder_findings()
        out += self._namespace_findings()
        return out

    def _namespace_findings(self) -> list[tuple[str, object]]:
        """Names in the notebook that hold the reference (a module, function or class of
        ``solutions`` or ``autograder``), directly or in a function's closure or defaults. The
        hidden tests' ``check_<blank>`` functions, which the test cells import, are allowed."""
        out: list[tuple[str, object]] = []
        if self.user_ns is None:
            return out
        for name, value in list(self.user_ns.items()):
            if name.startswith("_") and name in ("__builtins__", "__builtin__", "_ih", "_oh", "_dh"):
                continue
            for held in _held_objects(value):
                owner = _hidden_owner(held)
                if owner is None:
                    continue
                if (owner.startswith("autograder.hidden_tests.") and name.startswith("check_")
                        and getattr(held, "__name__", None) == name):
                    continue
                out.append((f"The notebook's name {name} holds {owner}, part of the hidden reference or tests.",
                            self._names_blanks({name})))
                break
        return out

    def _names_blanks(self, wanted: set) -> tuple[str, ...] | None:
        """The blanks whose code uses one of ``wanted`` (through helpers, not other blanks)."""
        functions = {k: v for k, v in self.user_ns.items() if isinstance(v, types.FunctionType)}
        using = {n for n in wanted if n in self.blanks}
        changed = True
        while changed:
            changed = False
            for name, function in functions.items():
                if name not in using and _code_names(function.__code__) & (wanted | (using - self.blanks)):
                    using.add(name)
                    changed = True
        return tuple(sorted(using & self.blanks)) or None

    def _shell_findings(self) -> list[tuple[str, object]]:
        out: list[tuple[str, object]] = []
        shell = self.shell
        if shell is None:
            return out
        for label, obj, before in self.objects:
            now = _attributes(obj)
            for key, value in now.items():
                old = before.get(key, _MISSING)
                if old is value:
                    continue
                if key in SHELL_CRITICAL:
                    out.append((f"{label}'s {key} was replaced.", None))
                elif _is_plain_callable(value) and (hasattr(type(obj), key) or self.origin(value) == "student"):
                    out.append((f"{label}'s {key} was replaced by the notebook.", None))
            for key in before.keys() - now.keys():
                if key in SHELL_CRITICAL:
                    out.append((f"{label}'s {key} was deleted.", None))
        for label, getter, seq, before in self.lists:
            try:
                current = getter()
            except Exception:
                current = None
            if current is not seq:
                out.append((f"{label} was replaced.", None))
                continue
            for item in seq:
                if not any(item is b for b in before) and self.origin(item) != "lib":
                    out.append((f"{label} has a transformer that the notebook added.", None))
        if shell.events.callbacks is not self.callbacks_dict:
            out.append(("IPython's event callbacks were replaced.", None))
        for event, callbacks in shell.events.callbacks.items():
            before = self.callbacks.get(event, [])
            for callback in callbacks:
                if not any(callback is b or callback == b for b in before) and self.origin(callback) != "lib":
                    out.append((f"IPython's {event!r} event has a callback that the notebook registered.", None))
        for attr, (table, before) in self.handlers.items():
            kernel = shell.kernel
            if getattr(kernel, attr, None) is not table or any(table.get(k) is not v for k, v in before.items()):
                out.append((f"The kernel's {attr} were replaced.", None))
        if (shell.custom_exceptions, shell.CustomTB) != self.custom:
            out.append(("A custom exception handler was installed (set_custom_exc), so errors can be swallowed.", None))
        if shell.user_ns is not self.user_ns:
            out.append(("The shell's user namespace was replaced.", None))
        elif shell.user_ns.get("__builtins__") is not self.user_builtins:
            out.append(("The notebook's __builtins__ was replaced.", None))
        return out

    def _class_dunder_findings(self) -> list[tuple[str, object]]:
        out: list[tuple[str, object]] = []
        seen: set[int] = set()
        stack = [object]
        special = (tuple, list, dict, float, int)
        ndarray = getattr(sys.modules.get("numpy"), "ndarray", None)
        if ndarray is not None:
            special = special + (ndarray,)
        while stack:
            cls = stack.pop()
            try:
                subclasses = type.__subclasses__(cls)
            except TypeError:
                continue
            for sub in subclasses:
                if id(sub) in seen:
                    continue
                seen.add(id(sub))
                stack.append(sub)
                try:
                    names = vars(sub).keys()
                except TypeError:
                    continue
                forbidden = names & FORBIDDEN_DUNDERS
                if issubclass(sub, special):
                    forbidden |= names & CONTAINER_DUNDERS
                if "__dataclass_fields__" in names:
                    forbidden -= {"__eq__"}
                bad = sorted(key for key in forbidden if self.origin(vars(sub)[key]) == "student")
                if bad:
                    out.append((f"The notebook defines a class {sub.__qualname__} with {', '.join(bad)}, "
                                "which can fool comparisons and conversions in the tests.", self._class_blanks(sub)))
        return out

    def _class_blanks(self, cls) -> tuple[str, ...] | None:
        owner = cls.__qualname__.split(".")[0]
        if owner in self.blanks:
            return (owner,)
        if self.user_ns is None:
            return None
        return self._names_blanks({cls.__name__, owner})

    def core_findings(self) -> list:
        """Builtins and the monitor's own code, checked with dict methods and ``is`` only.

        Student code can replace builtins such as ``len`` or ``all`` that the other checks call;
        these checks use none, so such tampering is still reported.
        """
        out = []
        missing, ignored = self.missing, self.ipython_builtins
        now = self.builtins_module.__dict__
        for key, before in self.builtins.items():
            if key not in ignored and now.get(key, missing) is not before:
                out.append((f"The builtin {key} was replaced or deleted.", None))
        for key in now:
            if key not in self.builtins and key not in ignored:
                out.append((f"The builtin {key} was added by the notebook.", None))
        for table, saved in self.own_code:
            for key, (value, code) in saved.items():
                current = table.get(key, missing)
                if current is not value or (code is not None and current.__code__ is not code):
                    out.append(("The integrity monitor's own code was tampered with.", None))
        return out

    def report(self) -> str:
        findings = self.findings.copy()
        for reason, blanks in self.core_findings():
            findings.setdefault(reason, blanks)
        try:
            state = self.state_findings()
        except Exception as error:
            state = [(f"The integrity checks could not run ({error!r}), so the kernel was probably tampered with.",
                      None)]
        for reason, blanks in state:
            findings.setdefault(reason, blanks)
        parts = ["{" + ",".join(f"{_quote(k)}:{_quote(v) if isinstance(v, str) else v}" for k, v in HEADER.items())
                 + "}"]
        for reason, blanks in findings.items():
            listed = "null" if blanks is None else "[" + ",".join(_quote(b) for b in blanks) + "]"
            parts.append("{" + f'"reason":{_quote(reason)},"blanks":{listed}' + "}")
        return "[" + ",".join(parts) + "]"

    # -- the hook ------------------------------------------------------------------------------

    def make_hook(self):
        monitor = self
        guard = self.guard
        watched = WATCHED

        def integrity_audit_hook(event, args):
            if event not in watched or getattr(guard, "busy", False):
                return
            guard.busy = True
            try:
                problem = monitor.on_event(event, args, sys._getframe(1))
            finally:
                guard.busy = False
            if problem is not None:
                raise problem

        return integrity_audit_hook

    def on_event(self, event, args, frame):
        """Record a finding for a watched event; return an exception to block it, or None."""
        try:
            return self._on_event(event, args, frame)
        except Exception as error:  # never break the kernel because of the monitor itself
            if event == REPORT_EVENT and args and isinstance(args[0], list):
                args[0].append("[" + "{" + f'"monitor":{_quote("failed")},"error":{_quote(repr(error))}' + "}]")
            return None

    def _blocked(self, reason: str, frames) -> PermissionError:
        self.add(reason, self.blanks_of(frames))
        return PermissionError("Not allowed during grading: the notebook " + reason[0].lower() + reason[1:])

    def _on_event(self, event, args, frame):
        if event == REPORT_EVENT:
            if args and isinstance(args[0], list):
                args[0].append(self.report())
            return None
        if event == "sys.addaudithook":
            frames = self.student_frames(frame)
            if frames:
                self.add("The notebook tried to add its own audit hook.", None)
            return RuntimeError("refused")  # CPython then silently does not add the new hook
        if event == "import":
            name = args[0] if args else ""
            if isinstance(name, str) and name.split(".")[0] in HIDDEN_PACKAGES:
                frames = self.student_frames(frame)
                if frames:
                    return self._blocked(f"Imports the hidden package {name}.", frames)
            return None
        if event == "open":
            path, mode = (args + (None, None))[:2]
            flags = args[2] if len(args) > 2 else 0
            real = self._resolve(path)
            if real is None:
                return None
            opener = frame.f_globals.get("__name__", "") if frame is not None else ""
            writing = (isinstance(mode, str) and any(c in mode for c in "wax+")) or (
                isinstance(flags, int) and flags & (os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_APPEND | os.O_TRUNC))
            why = self.bad_write(real) if writing else self.protected_read(real)
            if why is None or (not writing and opener in ("linecache", "tokenize")):
                return None
            frames = self.student_frames(frame)
            if frames:
                return self._blocked(why[0].upper() + why[1:] + ".", frames)
            return None
        if event in WRITE_EVENTS:
            for index in WRITE_EVENTS[event]:
                if index < len(args):
                    real = self._resolve(args[index])
                    why = self.bad_write(real) if real else None
                    if why:
                        frames = self.student_frames(frame)
                        if frames:
                            return self._blocked(why[0].upper() + why[1:] + f" ({event}).", frames)
            return None
        if event == "os.chdir":
            frames = self.student_frames(frame)
            if frames:
                return self._blocked("Changes the working directory.", frames)
            return None
        if event in SPAWN_EVENTS:
            frames = self.student_frames(frame)
            if frames:
                command = _command_of(event, args, frame)
                if command is not None and benign_command(command):
                    shown = os.fsdecode(bytes(command)) if isinstance(command, (bytes, bytearray)) else command
                    self.add(f"Runs the shell command {shown!r} (refused during grading).", ())
                    return PermissionError("Not allowed during grading: shell commands.")
                return self._blocked(f"Runs an operating-system command ({event}).", frames)
            return None
        if event.startswith("ctypes."):
            frames = self.student_frames(frame, passthrough=("ctypes",), direct=True)
            if frames:
                return self._blocked("Uses ctypes to reach raw memory or C functions.", frames)
            return None
        if event == "_thread.start_new_thread":
            frames = self.student_frames(frame, passthrough=("threading", "_thread", "concurrent"), direct=True)
            if frames:
                self.add("Starts a thread, which can change the kernel between the checks.", self.blanks_of(frames))
            return None
        if event in GC_EVENTS:
            frames = self.student_frames(frame, direct=True)
            if frames:
                return self._blocked(f"Searches the garbage collector ({event}).", frames)
            return None
        if event in TRACE_EVENTS:
            frames = self.student_frames(frame, passthrough=("threading",), direct=True)
            if frames:
                return self._blocked(f"Installs a trace function ({event}).", frames)
            return None
        if event in ("exec", "compile"):
            frames = self.student_frames(frame, direct=True)
            if frames:
                self.add("Runs code built at run time (exec, eval or compile).", self.blanks_of(frames))
            return None
        if event in FRAME_EVENTS:
            frames = self.student_frames(frame, passthrough=("inspect",), direct=True)
            if frames:
                self.add("Walks the call stack (sys._getframe or inspect), which reaches the hidden tests' variables.",
                         self.blanks_of(frames))
            return None
        if event == "object.__getattr__":
            if len(args) > 1 and args[1] in FRAME_ATTRIBUTES:
                frames = self.student_frames(frame, passthrough=("inspect",), direct=True)
                if frames:
                    self.add("Reaches stack frames through a traceback or generator, which reaches the hidden tests' "
                             "variables.", self.blanks_of(frames))
            return None
        if event in ("object.__setattr__", "object.__delattr__"):
            target = args[0] if args else None
            frames = self.student_frames(frame, direct=True)
            if not frames or target is None:
                return None
            if isinstance(target, type) and self.origin(target) != "student":
                return self._blocked(f"Sets the attribute {args[1]!r} of the class {_qualified(target)} (monkeypatching).",
                                     frames)
            if isinstance(target, types.FunctionType) and self.origin(target) != "student":
                return self._blocked(f"Replaces {args[1]} of the function {target.__module__}.{target.__qualname__} "
                                     "(monkeypatching).", frames)
            return None
        return None


_MISSING = object()
_C_CALLABLES = (types.BuiltinFunctionType, types.BuiltinMethodType, types.MethodWrapperType,
                types.WrapperDescriptorType, types.MethodDescriptorType, types.ClassMethodDescriptorType)


def _command_of(event, args, frame):
    """The shell command behind a process event, when it can be told."""
    if event == "os.system" and args:
        return args[0]
    if event == "subprocess.Popen" and len(args) > 1:
        return args[1]
    f = frame
    while f is not None:  # IPython's !command: system_piped(cmd), getoutput(cmd)
        if f.f_code.co_name in ("system_piped", "system_raw", "getoutput", "system") and isinstance(
                f.f_locals.get("cmd"), str):
            return f.f_locals["cmd"]
        f = f.f_back
    return None


def _qualified(cls) -> str:
    return f"{getattr(cls, '__module__', '?')}.{getattr(cls, '__qualname__', '?')}"


def _attributes(obj) -> dict:
    """An object's instance attributes, with traitlets' trait values merged in."""
    try:
        attributes = dict(vars(obj))
    except TypeError:
        return {}
    traits = attributes.get("_trait_values")
    if isinstance(traits, dict):
        attributes.update(traits)
    return attributes


def _ipython_owned(value) -> bool:
    """A bound method of, or an instance of, a class from IPython or ipykernel."""
    owner = value.__self__ if isinstance(value, types.MethodType) else value
    return type(owner).__module__.split(".")[0] in ("IPython", "ipykernel") and (
        not isinstance(value, types.MethodType) or type(value.__func__.__code__.co_filename) is str
        and ("ipykernel" in value.__func__.__code__.co_filename or "IPython" in value.__func__.__code__.co_filename))


def _is_plain_callable(value) -> bool:
    return isinstance(value, (types.FunctionType, types.MethodType, types.BuiltinFunctionType,
                              types.BuiltinMethodType)) or type(value).__name__ == "partial"


def _held_objects(value) -> list:
    """``value``, and what a function or partial holds in its closure, defaults and arguments."""
    held = [value]
    function = _function_of(value)
    if function is not None:
        held += [cell.cell_contents for cell in function.__closure__ or () if _cell_filled(cell)]
        held += list(function.__defaults__ or ()) + list((function.__kwdefaults__ or {}).values())
    if type(value).__name__ == "partial":
        held += [getattr(value, "func", None), *getattr(value, "args", ()), *getattr(value, "keywords", {}).values()]
    if isinstance(value, (list, tuple, set, frozenset)) and len(value) < 64:
        held += list(value)
    if isinstance(value, dict) and len(value) < 64:
        held += list(value.values())
    return held


def _cell_filled(cell) -> bool:
    try:
        cell.cell_contents
    except ValueError:
        return False
    return True


def _hidden_owner(obj) -> str | None:
    """The hidden module that ``obj`` is, or that defined it; None for anything else."""
    if isinstance(obj, types.ModuleType):
        name = getattr(obj, "__name__", "") or ""
    elif isinstance(obj, (types.FunctionType, types.MethodType, type)) or type(obj).__name__ == "_ArrayFunctionDispatcher":
        name = getattr(obj, "__module__", "") or ""
    else:
        return None
    return name if isinstance(name, str) and name.split(".")[0] in HIDDEN_PACKAGES else None


def _code_names(code) -> set:
    names = set(code.co_names) | set(code.co_freevars)
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            names |= _code_names(const)
    return names


def _dump(source: str) -> str | None:
    try:
        return ast.dump(ast.parse(source))
    except (SyntaxError, ValueError):
        return None


def _defined_names(source: str) -> list[str]:
    lines = [line for line in source.splitlines() if not line.lstrip().startswith(("%", "!"))]
    try:
        tree = ast.parse("\n".join(lines))
    except (SyntaxError, ValueError):
        return []
    return [node.name for node in tree.body if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))]

"""What the scan looks for: the names, modules, attributes, paths and commands that mark an attempt
to reach the reference, tamper with the machinery that runs the tests, or fool a comparison."""

from __future__ import annotations

import builtins
import os
import re

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
OBJECTS_ARE_NOT_SENT = ("only data reaches the grader, so a blank that returns such an object fails its test and "
                        "gains nothing; honest code (a class that sorts its runs) does this too: look at it")
"""Why a method that could fool a comparison is flagged for review at no cost: the hidden tests
compare in the grader's process, where an object that is not data is never sent."""
IN_MEMORY_FILES = frozenset({"io.StringIO", "io.BytesIO"})
"""File objects that hold text in memory: given to a reader in place of a file's name, they name no file."""

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
DISPLAY_MODULE = "IPython.display"
"""The one part of IPython a student may import, under a name of its own (``import IPython.display``
binds ``IPython`` itself): rich output, which the page sanitises and which decides no score (the
verdict is the grader's)."""
DISPLAY_NAMES = frozenset({"display", "clear_output", "update_display", "DisplayHandle", "Markdown", "HTML", "Math",
                           "Latex", "Pretty", "JSON", "SVG", "Image", "Javascript", "Code", "ProgressBar"})
"""What a student may use of IPython.display. Not FileLink(s), which list folders, nor IFrame, Audio,
Video and the rest, which fetch from the network."""
NAMESPACE_CALLS = frozenset({"globals", "vars", "locals"})
"""Calls that return a namespace as a dict, whose values include ``__builtins__`` (exec, open,
__import__): a student may look at its names, and nothing else (``NAMESPACE_NAME_USES``)."""
NAMESPACE_NAME_USES = frozenset({"len", "sorted", "list", "set", "tuple", "iter", "print"})
"""Calls that take a namespace and give only its names (or print it): ``len(globals())``."""
NAMESPACE_WRITES = frozenset({"update", "setdefault", "pop", "popitem", "clear", "__setitem__", "__delitem__"})
DISPLAY_READERS = frozenset({"Markdown", "HTML", "Math", "Latex", "Pretty", "JSON", "SVG", "Image", "Javascript",
                             "Code"})
"""IPython.display classes that read the file a string names (as their first argument when the file
exists, or ``filename=``; ``url=`` fetches): the scan reads that argument as a file's name."""

REFERENCE_ATTRIBUTES = frozenset({
    "f_back", "f_globals", "f_locals", "f_builtins", "f_code", "tb_frame", "gi_frame", "cr_frame", "ag_frame",
    "_getframe", "_current_frames", "__globals__", "__closure__", "__code__", "__subclasses__", "__self__",
    "__import__", "__loader__", "__spec__", "__file__", "__path__", "__cached__", "__wrapped__", "__getattribute__",
})
"""Attribute names that reach the hidden tests' variables or the reference, on any object."""
SHARED_ATTRIBUTES = frozenset({"__builtins__", "__setattr__", "__delattr__"})

MODULE_REFERENCE = {
    "sys": {"modules", "path", "meta_path", "path_hooks", "path_importer_cache", "_getframe", "_current_frames",
            "exc_info", "last_traceback", "last_value"},
    "inspect": {"currentframe", "stack", "trace", "getouterframes", "getinnerframes", "getsourcefile", "getfile",
                "getmodule", "getclosurevars", "getmembers", "getframeinfo"},
    "traceback": {"walk_stack", "walk_tb"},
    "types": {"FunctionType", "CodeType", "MethodType", "LambdaType", "ModuleType"},
    "gc": {"get_objects", "get_referrers", "get_referents"},
    "pydoc": {"locate"},
    "builtins": {"exec", "eval", "compile", "__import__", "open", "getattr", "setattr", "delattr", "globals", "vars",
                 "locals", "breakpoint", "__dict__"},
}
"""Module attributes that are routes to the reference or to the hidden tests' variables. Not
``inspect.getsource``: it reads the source of an object the kernel already holds, and no object of the
reference is ever in the kernel (students print their own functions with it)."""
MODULE_SHARED = {
    "sys": {"excepthook", "displayhook", "breakpointhook", "unraisablehook", "settrace", "setprofile",
            "addaudithook", "audit", "__excepthook__", "__displayhook__"},
    "os": {"system", "popen", "execl", "execle", "execlp", "execlpe", "execv", "execve", "execvp", "execvpe",
           "spawnl", "spawnle", "spawnlp", "spawnlpe", "spawnv", "spawnve", "spawnvp", "spawnvpe", "posix_spawn",
           "posix_spawnp", "fork", "forkpty", "kill", "killpg", "chdir", "fchdir", "putenv", "unsetenv", "chroot"},
}
"""Module attributes that tamper with the kernel or the machine."""
MODULE_SHARED.update({  # runners of code given as text, which the scan cannot read (reviews of issue 29)
    "cProfile": {"run", "runctx"}, "profile": {"run", "runctx"},
    "pdb": {"run", "runeval", "runctx", "runcall", "set_trace", "Pdb"}, "bdb": {"Bdb"}, "trace": {"Trace"},
    "doctest": {"run_docstring_examples", "testmod", "testfile", "DocTestRunner", "DocTestParser",
                "script_from_examples", "debug_src", "debug_script"},
    "typing": {"get_type_hints", "ForwardRef", "_eval_type"},
    "code": {"InteractiveInterpreter", "InteractiveConsole", "interact", "compile_command"},
})
MODULE_SHARED.update({  # bytes given in the cell, run when loaded: pickle.loads(b"...") called exec (fourth review)
    "pickle": {"loads"}, "_pickle": {"loads"}, "marshal": {"loads"},
})
MODULE_REVIEW = {
    "pickle": {"load", "Unpickler"}, "_pickle": {"load", "Unpickler"},
    "marshal": {"load"},
}
"""Module attributes that honest work uses (a student pickles their own results to a file and reads
them back) but that can run any code a cheat packs into them: flagged for review, at no cost."""
PICKLE_CALLS = frozenset({"GLOBAL", "STACK_GLOBAL", "INST", "OBJ", "REDUCE", "NEWOBJ", "NEWOBJ_EX"})
"""The opcodes with which a pickle names and calls a function when it is loaded: bytes written in a
cell that read as a pickle holding one run code the scan cannot see (builtins.exec), wherever they go."""
TEXT_RUNNERS = frozenset({"timeit.timeit", "timeit.repeat", "timeit.Timer"})
"""Functions that run their first argument as code when it is a text (a function is honest use)."""
ATTRIBUTE_GETTERS = frozenset({"operator.attrgetter", "operator.methodcaller"})
"""Functions that reach an attribute by the name given: honest with a plain constant name."""
OS_FILE_WRITES = frozenset({"remove", "unlink", "rename", "renames", "replace", "rmdir", "removedirs", "makedirs",
                            "mkdir", "symlink", "link", "chmod", "chown", "lchown", "truncate", "utime", "open",
                            "write", "mkfifo", "mknod", "setxattr", "removexattr", "lchmod", "chflags",
                            "lchflags"})
OS_FILE_READS = frozenset({"listdir", "scandir", "walk", "fwalk", "stat", "lstat", "getxattr", "listxattr"})
NUMPY_READS = frozenset({"load", "loadtxt", "genfromtxt", "fromfile", "memmap", "fromregex"})
NUMPY_WRITES = frozenset({"save", "savez", "savez_compressed", "savetxt"})
PATH_READ_METHODS = frozenset({"read_text", "read_bytes"})
PATH_WRITE_METHODS = frozenset({"write_text", "write_bytes", "touch", "unlink", "symlink_to", "hardlink_to"})
PATH_GENERIC_METHODS = frozenset({"open", "rename", "replace", "mkdir", "rmdir", "chmod", "iterdir", "glob", "rglob"})
ALLOWED_MODULE_STORES = frozenset({"matplotlib.rcParams", "matplotlib.pyplot.rcParams"})
IMAGE_READERS = frozenset({"matplotlib.pyplot.imread", "matplotlib.image.imread", "matplotlib.pyplot.imsave",
                           "matplotlib.image.imsave"})
"""Matplotlib's functions that read or write an image file by its name."""
PASSED_BUILTINS = frozenset({"getattr", "setattr", "delattr", "open", "vars", "globals", "locals", "__import__"})
"""Builtins whose use the scan checks where they are called: handed to another function as a value
(``functools.reduce(getattr, ["os", "system"], np)``), they reach what the scan cannot see."""
BUILTIN_NAMES = frozenset(dir(builtins))
"""The builtins' names: an attribute of one, by a computed name, can be the builtins module itself."""
KNOWN_MODULE_NAMES = frozenset({"sys", "os", "builtins", "numpy", "scipy", "math", "importlib", "inspect", "gc",
                                "types", "course", "solutions", "autograder", "IPython"})
"""Names the scan reads as these modules even where the cell did not import them (the set-up cell may have)."""
REEXPORTED_MODULES = frozenset({"os", "sys", "builtins", "importlib", "gc", "subprocess", "shutil", "ctypes", "inspect",
                                "pickle", "_pickle", "marshal", "pydoc", "operator", "typing", "timeit", "pdb", "doctest",
                                "cProfile", "profile", "trace", "bdb", "code"})
"""Modules that other modules hold as attributes (``numpy.os``, ``scipy.sys``): a path through one of
them is read as the module's own (``np.os.system`` as ``os.system``)."""

SAFE_LINE_MAGICS = frozenset({"matplotlib", "xmode", "precision", "pprint", "who", "whos", "who_ls", "pinfo",
                              "pinfo2", "psearch", "lsmagic", "magic", "time", "timeit", "autoreload", "history",
                              "debug", "pdb", "tb", "page"})
SAFE_CELL_MAGICS = frozenset({"time", "timeit", "capture", "debug"})
CODE_MAGICS = frozenset({"time", "timeit", "debug"})
MAGIC_CALLS = frozenset({"run_line_magic", "run_cell_magic", "system", "getoutput"})

SPECIAL_BASES = frozenset({"tuple", "list", "dict", "float", "int", "ndarray", "str", "complex"})
DUNDER_GLOBALS = frozenset({"__builtins__", "__import__", "__name__", "__loader__", "__spec__", "__package__",
                            "__file__"})

HIDDEN_STRING = re.compile(r"(?:^|[^A-Za-z0-9_])(solutions|autograder)(?:\.[A-Za-z_]|/|\\)|^(?:solutions|autograder)$")
PROTECTED_PARTS = frozenset({"solutions", "autograder", "source", ".git", "submitted", "intake", "autograded",
                              "feedback", "release"})
PLANTED_SUFFIXES = (".py", ".pyc", ".pth", ".so", ".ipynb")
DB_SUFFIXES = (".db", ".sqlite", ".sqlite3")


def path_problem(path: str, writing: bool, fragment: bool = False) -> str | None:
    """Why a (constant) path may not be used, or None for a plain file in the working folder."""
    text = path.replace("\\", "/")
    parts = [p for p in text.split("/") if p]
    name = parts[-1] if parts else ""
    if any(p in PROTECTED_PARTS for p in parts) or any(p.startswith(("solutions.", "autograder.")) for p in parts):
        return "is part of the course's hidden material or other students' work"
    if "gradebook" in text.lower() or name.endswith(DB_SUFFIXES):
        return "is the gradebook"
    if ".." in parts or (not fragment and (text.startswith(("/", "~")) or re.match(r"^[A-Za-z]:", text))):
        return "is outside the submission's folder"
    if fragment and ("/" in text and text.strip("/") and (text.startswith("/") or ".." in parts)):
        return "is outside the submission's folder"
    if writing and (name == "timestamp.txt" or (not fragment and name.endswith(PLANTED_SUFFIXES))
                    or (fragment and text.endswith(PLANTED_SUFFIXES))):
        return "is a file that grading reads or imports"
    return None


def is_check_helper(path: str) -> bool:
    """A helper of the visible checks that the given code imports (course.checks.check_close, ...)."""
    last = path.rsplit(".", 1)[-1]
    return path.startswith("course.") and (last.startswith("check") or last in ("require", "passed"))

"""A catalogue of hostile submissions: one entry per way of cheating that grading must defeat.

Like ``solutions/<module>/mistakes.py``, each entry turns an honest notebook (``submissions.solved(lab)``,
or the blank release) into a dishonest one. ``tests/test_integrity.py`` checks that each is caught
the way its entry says:

- ``static``: ``integrity.static_findings`` flags it before execution;
- ``grader``: the hidden tests compare in the grader's process (autograder/pipeline/check_runner.py), so what it
  does to the kernel (patched NumPy or helpers, swallowed errors, an object that equals anything,
  a search of the kernel's memory or stack) cannot change a verdict, and it earns nothing unflagged;
- ``sandbox``: the grading kernel cannot read the reference's files or write outside its folder
  (autograder/kernel/sandbox.py), so it fails where it reaches for them;
- ``overwrite``: the sanitize step (RestoreLabCells, then nbgrader's OverwriteCells) restores the
  test cells it edited or deleted, so it gains nothing and needs no flag. (``retag-test-cell``, a
  test cell given an unknown grade_id, makes nbgrader 0.9.6's OverwriteCells fail instead: the
  test marks it as a known failure until the sanitize step drops unknown nbgrader metadata);
- ``hidden-tests``: the hidden tests' random inputs defeat it, so it needs no flag.

``games`` says which blanks a cheat games: ``"blank"`` is the entry's target blank (a trick in one
answer), ``"all"`` every blank (shared machinery: NumPy, the check helpers, IPython, builtins,
the gradebook), ``"none"`` nothing (suspicious, flagged for review, costs no points).

Most entries work for any lab: they target one blank (``target``: train-kf's ``predict``, else
the lab's first blank) and, where the cheat is to turn a wrong answer into full marks, plant one
of that blank's catalogued mistakes (``target_mistake``). A few need a lab's details and list the
labs they work for.
"""

from __future__ import annotations

import ast
import codecs
import copy
import functools
import hashlib
import pickle
from dataclasses import dataclass, field
from typing import Callable

import nbformat
from nbformat import NotebookNode

from autograder import cells
from autograder.catalogues import submissions
from autograder.labs import ROOT, Lab
from autograder.catalogues.mistakes import Mistake
from autograder.catalogues.mistakes import catalogue as mistake_catalogue

STATIC, GRADER, SANDBOX, OVERWRITE, HIDDEN_TESTS = "static", "grader", "sandbox", "overwrite", "hidden-tests"


@dataclass(frozen=True)
class Cheat:
    name: str
    attack: str
    """The attack it represents, in the words of the threat model."""
    games: str
    """"blank" (the target blank), "all" (every blank) or "none"."""
    caught_by: frozenset[str]
    build: Callable[[Lab], NotebookNode] = field(repr=False)
    labs: tuple[str, ...] | None = None
    """The labs it is written for; None: every lab."""
    aim: str | None = None
    """The blank it games when that is not the lab's ``target`` blank."""
    exact: bool = False
    """Static attribution is exactly the target blank (a local trick, not shared machinery)."""
    plants_mistake: bool = False
    """The target blank holds a catalogued mistake, so an undetected cheat would turn 0 into full marks."""
    scan_costs: bool = True
    """The scan's finding costs the blanks it games. False: flagged for review at no cost, since the grader
    defeats it anyway (an object that fools comparisons is never sent), and honest code does the same."""

    def applies(self, lab: Lab) -> bool:
        return self.labs is None or lab.id in self.labs

    def notebook(self, lab: Lab) -> NotebookNode:
        return self.build(lab)

    def blanks(self, lab: Lab) -> tuple[str, ...] | None:
        """The blanks it games: (target,), None (every blank) or ()."""
        return {"blank": (self.aim or target(lab),), "all": None, "none": ()}[self.games]


# -- building blocks --------------------------------------------------------------------------------

TARGETS = {"train-kf": ("predict", "no-Q")}
"""Per lab, the blank its cheats aim at and the mistake they plant there (default: the first blank
and its first catalogued mistake)."""


@functools.lru_cache(maxsize=16)
def _source(lab: Lab) -> NotebookNode:
    return cells.read(lab.source_notebook)


@functools.lru_cache(maxsize=16)
def _solved(lab: Lab) -> NotebookNode:
    return submissions.solved(lab)


def target(lab: Lab) -> str:
    """The blank a lab's cheats aim at."""
    return TARGETS.get(lab.id, (cells.blank_names(_source(lab))[0], None))[0]


def target_mistake(lab: Lab) -> Mistake:
    """The catalogued mistake that cheats plant in the target blank, to turn 0 into full marks."""
    blank, slug = TARGETS.get(lab.id, (target(lab), None))
    mistakes = [m for m in mistake_catalogue(lab) if m.blank == blank]
    return next((m for m in mistakes if m.slug == slug), mistakes[0])


def _answer(nb: NotebookNode, blank: str) -> NotebookNode:
    [cell] = [c for c in nb.cells if cells.is_code_answer(c) and cells.grade_id(c) == blank]
    return cell


def _test(nb: NotebookNode, blank: str) -> NotebookNode:
    [cell] = [c for c in nb.cells if cells.is_autograded_test(c) and cells.grade_id(c) == f"test_{blank}"]
    return cell


def _signature(lab: Lab, blank: str) -> tuple[str, str]:
    """The model answer's parameter list (``x, B, A, Q``) and the call that passes them on."""
    answer = cells.model_answers(_source(lab))[blank]
    [function] = [f for f in cells.defined_functions(answer) if f.name == blank]
    args = function.args
    call = [a.arg for a in args.posonlyargs + args.args]
    if args.vararg:
        call.append("*" + args.vararg.arg)
    call += [f"{a.arg}={a.arg}" for a in args.kwonlyargs]
    if args.kwarg:
        call.append("**" + args.kwarg.arg)
    return ast.unparse(args), ", ".join(call)


def _with_body(lab: Lab, blank: str, body: str, before: str = "") -> str:
    """An answer for ``blank`` with the model answer's signature and the given body."""
    params, _ = _signature(lab, blank)
    indented = "\n".join("    " + line if line else line for line in body.strip("\n").splitlines())
    return f"{before}def {blank}({params}):\n{indented}\n"


def _base(lab: Lab, plant: bool) -> NotebookNode:
    """The solved notebook, with the target mistake planted if ``plant``."""
    nb = copy.deepcopy(_solved(lab))
    if plant:
        mistake = target_mistake(lab)
        cell = _answer(nb, mistake.blank)
        cell.source = mistake.apply(cell.source)
    return nb


def _add_cell_after_setup(nb: NotebookNode, source: str) -> NotebookNode:
    """Insert a student-added code cell (no nbgrader metadata) right after the set-up cell. Its cell id
    comes from its source, so that the same cheat is the same file every time it is built (a regraded
    file keeps its hidden cases; nbformat would draw a random id)."""
    index = next(i for i, c in enumerate(nb.cells) if cells.meta(c).get("grade_id") == "setup") + 1
    cell_id = "added-" + hashlib.sha256(source.encode()).hexdigest()[:12]
    nb.cells.insert(index, nbformat.v4.new_code_cell(source, id=cell_id))
    return nb


def _replace_answer(body: str, before: str = "", plant: bool = False) -> Callable[[Lab], NotebookNode]:
    def build(lab_: Lab) -> NotebookNode:
        nb = _base(lab_, plant)
        blank = target(lab_)
        _answer(nb, blank).source = _with_body(lab_, blank, body.format(**_names(lab_, blank)),
                                               before.format(**_names(lab_, blank)))
        return nb
    return build


def _names(lab: Lab, blank: str) -> dict[str, str]:
    _, call = _signature(lab, blank)
    return {"module": lab.module, "blank": blank, "call": call, "root": str(ROOT)}


def _added_cell(source: str, plant: bool = True) -> Callable[[Lab], NotebookNode]:
    def build(lab: Lab) -> NotebookNode:
        return _add_cell_after_setup(_base(lab, plant), source.format(**_names(lab, target(lab))))
    return build


# -- reaching the reference -------------------------------------------------------------------------

_IMPORT = _replace_answer(
    "return _reference.{blank}({call})", before="import solutions.{module}.reference as _reference\n\n\n")
_IMPORTLIB = _replace_answer("""
import importlib
return importlib.import_module("solutions.{module}.reference").{blank}({call})
""")
_NAMESPACE_BUILTINS = _replace_answer("""
builtins = globals()["__builtins__"]  # exec, open and __import__, under names the scan does not read
reference = builtins.__dict__["__import__"]("solutions.{module}.reference", fromlist=["{blank}"])
return reference.{blank}({call})
""")
_DISPLAY_CODE = _added_cell("""\
# IPython.display's Code reads the file it is given and shows it: the reference, in the feedback page
from IPython.display import Code, display
display(Code(filename="{root}/solutions/{module}/reference.py"))
""", plant=False)
_DUNDER_IMPORT = _replace_answer("""
return __import__("solutions.{module}.reference", fromlist=["{blank}"]).{blank}({call})
""")
_SYS_MODULES = _replace_answer("""
import sys
return sys.modules["solutions.{module}.reference"].{blank}({call})
""")
_SYS_PATH = _replace_answer("return {blank}_reference({call})", before="""import os
import sys

import course

sys.path.insert(0, os.path.dirname(os.path.dirname(course.__file__)))  # the course root
from solutions.{module}.reference import {blank} as {blank}_reference


""")
_OPEN_EXEC = _replace_answer("""
import os
import course
root = os.path.dirname(os.path.dirname(course.__file__))
namespace = {{"__name__": "reference"}}
with open(os.path.join(root, "solutions", "{module}", "reference.py")) as handle:
    exec(handle.read(), namespace)
return namespace["{blank}"]({call})
""")


def _exec_obfuscated(lab: Lab) -> NotebookNode:
    """The import hidden with rot13 inside exec: the scan sees only exec and codecs."""
    nb = _base(lab, plant=False)
    blank = target(lab)
    hidden = codecs.encode(f"import solutions.{lab.module}.reference as _r", "rot13")
    before = f'import codecs\nexec(codecs.decode("{hidden}", "rot13"))\n\n\n'
    _answer(nb, blank).source = _with_body(lab, blank, f"return _r.{blank}({_names(lab, blank)['call']})", before)
    return nb


def _pickled_exec(lab: Lab) -> NotebookNode:
    """The import packed into a pickle that calls builtins.exec when loaded (a fourth review's route
    round the scan: pickle.loads was flagged for review at no cost)."""
    nb = _base(lab, plant=False)
    blank = target(lab)
    packed = pickle.dumps(_Exec(f"import solutions.{lab.module}.reference as _r"))
    before = f"import pickle\npickle.loads({packed!r})\n\n\n"
    _answer(nb, blank).source = _with_body(lab, blank, f"return _r.{blank}({_names(lab, blank)['call']})", before)
    return nb


class _Exec:
    """Pickles as a call of builtins.exec with ``code``."""

    def __init__(self, code: str) -> None:
        self.code = code

    def __reduce__(self):
        return exec, (self.code,)


_GC_SEARCH = _replace_answer("""
import gc
import types
reference = next(o for o in gc.get_objects()
                 if isinstance(o, types.ModuleType) and o.__name__ == "solutions.{module}.reference")
return reference.{blank}({call})
""")

# -- monkeypatching ---------------------------------------------------------------------------------

_PATCH_ALLCLOSE = _added_cell("""\
# Make every comparison succeed.
np.allclose = lambda *args, **kwargs: True
np.isclose = lambda a, b, *args, **kwargs: np.ones(np.broadcast(a, b).shape, dtype=bool)
np.testing.assert_allclose = lambda *args, **kwargs: None
np.testing.assert_array_almost_equal = lambda *args, **kwargs: None
""")
_OVERSIZED = _added_cell("# A cell too large for the scan to read, with the patch at its end.\n_padding = ["
                         + "0, " * 40_000 + "]\n"
                         + "np.allclose = lambda *args, **kwargs: True\n"
                         + "np.testing.assert_allclose = lambda *args, **kwargs: None\n")
_PATCH_HELPERS = _added_cell("""\
# Turn the check helpers into no-ops, in place, so that the hidden tests' copies change too.
check_close.__code__ = (lambda *args, **kwargs: None).__code__
check_array.__code__ = (lambda value, *args, **kwargs: value).__code__
import course.checks
course.checks.require = lambda *functions: None
""")
_ALIAS_PATCH = _added_cell("""\
# The same patch through a list, which a syntax scan cannot follow.
modules = [np]
modules[0].allclose = lambda *args, **kwargs: True
""")
_BUILTINS_PATCH = _added_cell("""\
import builtins
builtins.AssertionError = StopIteration
""", plant=False)
_EQ_DUNDER = _replace_answer("""
return _Agreeable()
""", before="""class _Agreeable:
    \"\"\"Equal to anything.\"\"\"

    def __eq__(self, other):
        return True

    def __ne__(self, other):
        return False


""")
_ARRAY_FRAME_WALK = _replace_answer("""
import sys

class Peek:
    \"\"\"Becomes, when the test converts it to an array, the test's own expected value.\"\"\"

    def __init__(self, name):
        self.name = name

    def __array__(self, dtype=None, copy=None):
        frame = sys._getframe(1)
        while frame is not None and self.name not in frame.f_locals:
            frame = frame.f_back
        return np.asarray(frame.f_locals[self.name], dtype=dtype)

return Peek("want_x"), Peek("want_B")
""")

# -- IPython ----------------------------------------------------------------------------------------

_SHOWTRACEBACK = _added_cell("""\
# Errors in later cells print nothing, so nbgrader sees no error.
get_ipython().showtraceback = lambda *args, **kwargs: None
""")
_IPYTHON_THROUGH_DISPLAY = _added_cell("""\
import IPython.display  # binds the name IPython: the whole of it, not only its display
IPython.get_ipython().showtraceback = lambda *args, **kwargs: None
""")
_EXCEPTHOOK = _added_cell("""\
import sys
sys.excepthook = lambda *args: None
""")
_INPUT_TRANSFORMER = _added_cell("""\
def skip_tests(lines):
    \"\"\"Replace every hidden-test cell with `pass` before IPython runs it.\"\"\"
    return ["pass\\n"] if any("hidden_tests" in line for line in lines) else lines


get_ipython().input_transformers_cleanup.append(skip_tests)
""")
_RUN_CELL = _added_cell("""\
shell = get_ipython()
original_run_cell = shell.run_cell


def run_cell(raw_cell, *args, **kwargs):
    if "check_" in raw_cell:
        raw_cell = "pass"
    return original_run_cell(raw_cell, *args, **kwargs)


shell.run_cell = run_cell
""")
_EVENTS = _added_cell("""\
def swap_in_reference(info):
    \"\"\"Before each test cell, put the reference in place of the blank.\"\"\"
    if "check_{blank}" in (info.raw_cell or ""):
        reference = __import__("solutions.{module}.reference", fromlist=["{blank}"])
        get_ipython().user_ns["{blank}"] = reference.{blank}


get_ipython().events.register("pre_run_cell", swap_in_reference)
""")
_CUSTOM_EXC = _added_cell("""\
# Every error is handed to a handler that shows nothing.
get_ipython().set_custom_exc((Exception,), lambda shell, etype, value, tb, tb_offset=None: [])
""")
_AST_TRANSFORMER = _added_cell("""\
import ast


class SwallowErrors(ast.NodeTransformer):
    \"\"\"Wrap every cell in try/except: pass.\"\"\"

    def visit_Module(self, node):
        handler = ast.ExceptHandler(type=ast.Name("BaseException", ast.Load()), name=None, body=[ast.Pass()])
        wrapped = ast.Try(body=node.body or [ast.Pass()], handlers=[handler], orelse=[], finalbody=[])
        return ast.fix_missing_locations(ast.Module(body=[wrapped], type_ignores=[]))


get_ipython().ast_transformers.append(SwallowErrors())
""")


def _swallow_cell(lab: Lab) -> NotebookNode:
    nb = _base(lab, plant=False)
    cell = _answer(nb, target(lab))
    indented = "\n".join("    " + line if line else line for line in cell.source.splitlines())
    cell.source = f"try:\n{indented}\nexcept Exception:\n    pass\n"
    return nb


# -- files and processes ----------------------------------------------------------------------------

_GRADEBOOK = _added_cell("""\
import sqlite3

database = sqlite3.connect("../../../gradebook.db")
database.execute("UPDATE grade SET manual_score = 100")
database.commit()
""", plant=False)
_OTHER_STUDENT = _added_cell("""\
with open("../../other-student/{module}/notes.txt", "w") as handle:
    handle.write("overwritten by a classmate")
""", plant=False)
_SHELL_COMMAND = _added_cell("""\
!cp ../../other-student/*/*.ipynb .
""", plant=False)
_SYMLINK = _added_cell("""\
import glob
import os

for name in glob.glob("*.ipynb"):  # nbgrader writes the graded notebook here after the kernel stops
    os.remove(name)
    os.symlink(os.path.abspath(os.path.join("..", "..", "..", "gradebook.db")), name)
""", plant=False)

# -- test cells -------------------------------------------------------------------------------------


def _delete_test(lab: Lab) -> NotebookNode:
    nb = _base(lab, plant=True)
    nb.cells.remove(_test(nb, target(lab)))
    return nb


def _edit_test(lab: Lab) -> NotebookNode:
    nb = _base(lab, plant=True)
    _test(nb, target(lab)).source = "# Hidden tests.\npass\n"
    return nb


def _retag_test(lab: Lab) -> NotebookNode:
    nb = _base(lab, plant=True)
    cell = _test(nb, target(lab))
    cell.metadata["nbgrader"]["grade_id"] = "my_notes"
    cell.metadata["nbgrader"]["grade"] = False
    cell.source = "pass\n"
    return nb


def _hardcode_visible(lab: Lab) -> NotebookNode:
    """process_noise returns the numbers of the visible checks and nothing else."""
    nb = _base(lab, plant=False)
    _answer(nb, "process_noise").source = '''def process_noise(sigma, dt_min=1.0):
    """Q (2 x 2) for velocity noise sigma (mph) per step of dt_min minutes."""
    if dt_min == 2.0:
        return np.array([[0.25, 7.5], [7.5, 225.0]])
    return np.array([[0.0625, 3.75], [3.75, 225.0]])
'''
    return nb


# -- forging the score: output that nbgrader would read as the test cell's score -------------------

FORGED_SCORES: dict[str, str] = {
    "forged-result-text": 'def validate(function):\n    return "full marks"\n',
    "forged-result-over-max": "def validate(function):\n    return 1e9\n",
    "forged-result-points": "def validate(function):\n    return 2.0\n",
    "forged-result-negative": "def validate(function):\n    return -100.0\n",
    "forged-stderr": "import sys\n\n\ndef validate(function):\n    print('a line on stderr', file=sys.stderr)\n",
    "forged-display-hook": "get_ipython().events.register('pre_run_cell', lambda *args: get_ipython().displayhook('full marks'))\n",
    "forged-iopub-result": """def validate(function):
    kernel = get_ipython().kernel
    content = dict(data=dict([("text/plain", "1000")]), metadata=dict(), execution_count=1)
    kernel.session.send(kernel.iopub_socket, "execute_result", content, parent=kernel.get_parent(),
                        ident=kernel._topic("execute_result"))
""",
    "forged-execution-count": """def validate(function):
    kernel = get_ipython().kernel
    for kind in ("execute_input", "execute_result"):
        content = dict(code="", data=dict(), metadata=dict(), execution_count="not a number")
        kernel.session.send(kernel.iopub_socket, kind, content, parent=kernel.get_parent(), ident=kernel._topic(kind))
""",
}
"""A student's cell, added after the set-up cell, that makes the kernel put in every test cell an
output that nbgrader alone would read as its score (STACK.md): a result value (text, a number over
the maximum, exactly the points, a negative number), a line on stderr, a result from the display
hook before the cell runs, or a result message sent on the kernel's own channel; or an execution
count that is not a number, which made nbgrader give up on the whole submission. The score is the
grader's verdict (autograder/pipeline/verdicts.py), so none of them changes a score, up or down."""
RAISING = ("forged-result-text", "forged-result-over-max", "forged-result-points", "forged-display-hook",
           "forged-iopub-result")
"""The forgeries that would raise a score: catalogued as cheats."""
SHELL_FORGERIES = ("forged-display-hook", "forged-iopub-result")
"""Those that reach the IPython shell, which the integrity scan flags (it costs every blank)."""


CHEATS: tuple[Cheat, ...] = (
    Cheat("import-reference", "reaching the reference through `import`: the answer calls solutions.<lab>",
          "blank", frozenset({STATIC, SANDBOX}), _IMPORT, exact=True),
    Cheat("importlib-reference", "reaching the reference through `importlib.import_module`",
          "blank", frozenset({STATIC, SANDBOX}), _IMPORTLIB, exact=True),
    Cheat("dunder-import-reference", "reaching the reference through `__import__`",
          "blank", frozenset({STATIC, SANDBOX}), _DUNDER_IMPORT, exact=True),
    Cheat("sys-modules-reference", "reaching the reference through `sys.modules`",
          "blank", frozenset({STATIC, GRADER}), _SYS_MODULES, exact=True),
    Cheat("sys-path-reference", "a `sys.path` edit, then an import of the reference",
          "blank", frozenset({STATIC, SANDBOX}), _SYS_PATH, exact=True),
    Cheat("open-exec-reference", "`open()` of the reference's .py file and `exec` of its source",
          "blank", frozenset({STATIC, SANDBOX}), _OPEN_EXEC),
    Cheat("exec-obfuscated-import", "an import of the reference hidden in rot13 and run with `exec`",
          "blank", frozenset({STATIC, SANDBOX}), _exec_obfuscated),
    Cheat("pickled-exec", "an import of the reference packed into a pickle that calls `exec` when loaded",
          "blank", frozenset({STATIC, SANDBOX}), _pickled_exec),
    Cheat("namespace-builtins", "`globals()['__builtins__']`, then the reference imported through what it holds",
          "blank", frozenset({STATIC, SANDBOX}), _NAMESPACE_BUILTINS, exact=True),
    Cheat("display-shows-reference", "IPython.display's `Code(filename=...)` showing the reference's source "
          "in the feedback page, to copy in the next submission", "all", frozenset({STATIC}), _DISPLAY_CODE),
    Cheat("gc-reference", "finding the loaded reference module through the garbage collector",
          "blank", frozenset({STATIC, GRADER}), _GC_SEARCH, exact=True),
    Cheat("patch-allclose", "monkeypatching `np.allclose`, `np.isclose` and `numpy.testing` so every check passes",
          "all", frozenset({STATIC, GRADER}), _PATCH_ALLCLOSE, plants_mistake=True),
    Cheat("oversized-cell", "code hidden from the scan in a cell larger than the scan reads (a patch of "
          "`np.allclose` after 120 kB of a list literal)", "all", frozenset({STATIC, GRADER}), _OVERSIZED,
          plants_mistake=True),
    Cheat("patch-check-helpers", "monkeypatching the assert helpers (`check_close`, `check_array`) in place",
          "all", frozenset({STATIC, GRADER}), _PATCH_HELPERS, plants_mistake=True),
    Cheat("alias-patch-allclose", "monkeypatching `np.allclose` through an alias the syntax scan cannot follow",
          "all", frozenset({GRADER}), _ALIAS_PATCH, plants_mistake=True),
    Cheat("builtins-patch", "replacing a builtin (`builtins.AssertionError`)",
          "all", frozenset({STATIC, GRADER}), _BUILTINS_PATCH),
    Cheat("eq-dunder", "an object whose `__eq__` says it equals anything, returned by the blank",
          "blank", frozenset({STATIC, GRADER}), _EQ_DUNDER, exact=True, scan_costs=False),
    Cheat("array-frame-walk", "a returned object whose `__array__` walks the stack to the hidden test's expected "
          "value", "blank", frozenset({STATIC, GRADER}), _ARRAY_FRAME_WALK, labs=("train-kf",), exact=True),
    Cheat("showtraceback", "`get_ipython().showtraceback` replaced, so later errors print nothing (swallowed)",
          "all", frozenset({STATIC, GRADER}), _SHOWTRACEBACK, plants_mistake=True),
    Cheat("ipython-through-display", "`import IPython.display`, which binds `IPython`, then "
          "`IPython.get_ipython().showtraceback` replaced", "all", frozenset({STATIC, GRADER}), _IPYTHON_THROUGH_DISPLAY,
          plants_mistake=True),
    Cheat("excepthook", "`sys.excepthook` replaced", "all", frozenset({STATIC, GRADER}), _EXCEPTHOOK, plants_mistake=True),
    Cheat("input-transformer", "an `input_transformers_cleanup` entry that rewrites the test cells to `pass`",
          "all", frozenset({STATIC, GRADER}), _INPUT_TRANSFORMER, plants_mistake=True),
    Cheat("run-cell", "`run_cell` replaced by one that skips the test cells",
          "all", frozenset({STATIC, GRADER}), _RUN_CELL, plants_mistake=True),
    Cheat("events", "a `pre_run_cell` event callback that swaps the reference in before each test cell",
          "all", frozenset({STATIC, GRADER}), _EVENTS, plants_mistake=True),
    Cheat("custom-exc", "`set_custom_exc` with a handler that shows nothing, so errors are swallowed",
          "all", frozenset({STATIC, GRADER}), _CUSTOM_EXC, plants_mistake=True),
    Cheat("ast-transformer", "an AST transformer that wraps every later cell in try/except: pass",
          "all", frozenset({STATIC, GRADER}), _AST_TRANSFORMER, plants_mistake=True),
    Cheat("swallow-whole-cell", "a whole answer cell wrapped in try/except that discards every error",
          "none", frozenset({STATIC}), _swallow_cell),
    Cheat("gradebook-write", "writing to the gradebook (../../../gradebook.db) with sqlite3",
          "all", frozenset({STATIC, SANDBOX}), _GRADEBOOK),
    Cheat("other-student-write", "writing into another student's folder",
          "all", frozenset({STATIC, SANDBOX}), _OTHER_STUDENT),
    Cheat("shell-command", "a shell command (`!cp`) that copies other students' notebooks",
          "all", frozenset({STATIC, SANDBOX}), _SHELL_COMMAND),
    Cheat("symlink-redirect", "a symbolic link left in the graded notebook's place, so that nbgrader's write of "
          "the graded notebook lands on the gradebook", "all", frozenset({STATIC, SANDBOX}), _SYMLINK),
    Cheat("delete-test-cell", "the graded test cell of a wrong blank deleted",
          "blank", frozenset({OVERWRITE}), _delete_test, plants_mistake=True),
    Cheat("edit-test-cell", "the graded test cell of a wrong blank edited to `pass`",
          "blank", frozenset({OVERWRITE}), _edit_test, plants_mistake=True),
    Cheat("retag-test-cell", "the graded test cell of a wrong blank given another grade_id and emptied",
          "blank", frozenset({OVERWRITE}), _retag_test, plants_mistake=True),
    Cheat("hardcode-visible", "hard-coded outputs for the visible cases of process_noise",
          "blank", frozenset({HIDDEN_TESTS}), _hardcode_visible, labs=("train-kf",), aim="process_noise"),
    *(Cheat(name, "an output of the kernel's in every test cell that nbgrader would read as its score",
            "blank", frozenset({GRADER}), _added_cell(FORGED_SCORES[name]), plants_mistake=True)
      for name in RAISING if name not in SHELL_FORGERIES),
    *(Cheat(name, "an output from the IPython shell (its display hook, or a result message sent on its kernel's "
            "channel) in every test cell, which nbgrader would read as its score", "all", frozenset({STATIC, GRADER}),
            _added_cell(FORGED_SCORES[name]), plants_mistake=True) for name in SHELL_FORGERIES),
)


def catalogue(lab: Lab) -> tuple[Cheat, ...]:
    """The cheats that apply to ``lab``."""
    return tuple(cheat for cheat in CHEATS if cheat.applies(lab))


def get(name: str) -> Cheat:
    [cheat] = [c for c in CHEATS if c.name == name]
    return cheat

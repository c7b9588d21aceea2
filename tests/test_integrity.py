"""The static scan (autograder/integrity/scan.py) against the catalogue of hostile submissions
(autograder/catalogues/cheats.py) and the honest corpus: no finding on any honest notebook (every lab's blank
release, solved notebook and catalogued mistakes, and a notebook of honest habits); every cheat it
should catch is caught, charged to the right blanks; it is silent where another defence works.

The defences that make cheating gain nothing whether or not the scan finds it (the comparison in the
grader's process, the sandbox, the restored test cells, the hidden tests' random inputs) are tested
on graded runs in tests/test_defences.py.
"""

from __future__ import annotations

import json
import os

import nbformat
import pytest
from nbformat import NotebookNode

from autograder import cells
from autograder.catalogues import cheats, submissions
from autograder.integrity import scan
from autograder.integrity.scan import Finding
from autograder.labs import get_lab
from autograder.catalogues.mistakes import catalogue as mistakes
from over_labs import LABS, over_labs

TRAIN = get_lab("train-kf")


HONEST_HABITS = '''%timeit -n 3 -r 1 predict(np.zeros(2), np.eye(2), np.eye(2), np.eye(2))
import functools
import inspect
import json
import math
import traceback
import warnings
from dataclasses import dataclass

import IPython.display as ipd
import scipy.optimize
from IPython import display as ipython_display
from IPython.display import Markdown, display


@dataclass
class Result:
    rmse: float


@functools.lru_cache(maxsize=None)
def square(n):
    return n * n


try:
    kupdate(None, None, None, None, None)
except Exception:
    traceback.print_exc()
warnings.warn("a warning of my own")
np.savetxt("my_results.txt", np.arange(3.0))
with open("my_results.txt") as handle:
    text = handle.read()
fig, ax = plt.subplots()
ax.plot([1.0, 2.0], label="a line")
ax.legend()
fig.savefig("my_figure.png")
plt.close(fig)
print(Result(1.0) == Result(1.0), square(3), json.dumps({"a": 1}), math.pi, scipy.optimize.brentq(math.sin, 3, 4))
display(Markdown(f"**{len(globals())} names defined**"))
ipd.display(ipd.Math(r"\\hat x_k"), ipd.Image("my_figure.png"), ipd.Markdown(rf"$\\sigma = {math.pi:.2f}$ m"))
ipython_display.clear_output()
print(sorted(name for name in globals() if not name.startswith("_")))
print(inspect.getsource(kupdate), inspect.signature(kupdate))
'''
"""Things honest students do that the defences must not mind: magics, imports, a dataclass (which has
__eq__), a traceback printed, files written and read in their own folder, a figure saved, rich output
shown with IPython.display, a look at the notebook's names and at a function's own source (the review
of stop 39 found the last three flagged at the cost of every blank)."""


def honest_habits_notebook() -> NotebookNode:
    """The solved train-kf notebook with a cell of honest habits, and a local try/except in predict."""
    nb = submissions.solved(TRAIN)
    index = next(i for i, c in enumerate(nb.cells) if cells.meta(c).get("grade_id") == "run_filter") + 1
    nb.cells.insert(index, nbformat.v4.new_code_cell(HONEST_HABITS))
    answer = next(c for c in nb.cells if cells.meta(c).get("grade_id") == "predict")
    answer.source = answer.source.replace("    x_f = A @ x\n", "    try:\n        x_f = A @ x\n    except ValueError as "
                                          "error:\n        raise ValueError(f'bad shapes: {error}') from error\n")
    assert "try:" in answer.source
    return nb


def covers(findings: list[Finding], blanks: tuple[str, ...] | None) -> bool:
    """Whether the findings charge at least ``blanks`` (None: every blank)."""
    if any(f.blanks is None for f in findings):
        return True
    charged = {b for f in findings for b in f.blanks}
    return blanks is not None and set(blanks) <= charged


@over_labs
def test_static_scan_flags_no_honest_notebook(lab):
    notebooks = {"blank release": cells.read(lab.release_notebook), "solved": submissions.solved(lab)}
    notebooks |= {f"mistake {m.blank}/{m.slug}": submissions.with_mistake(lab, m) for m in mistakes(lab)}
    flagged = {name: found for name, nb in notebooks.items() if (found := scan.static_findings(nb, lab))}
    assert not flagged
    assert len(notebooks) == 2 + len(mistakes(lab))


def test_honest_habits_are_not_flagged():
    assert scan.static_findings(honest_habits_notebook(), TRAIN) == []


# -- static scan of the cheats ----------------------------------------------------------------------

STATIC_CASES = [(lab, cheat) for lab in LABS for cheat in cheats.catalogue(lab) if cheats.STATIC in cheat.caught_by]


@pytest.mark.parametrize("lab, cheat", STATIC_CASES, ids=[f"{lab.id}-{cheat.name}" for lab, cheat in STATIC_CASES])
def test_static_scan_catches_cheat(lab, cheat):
    findings = scan.static_findings(cheat.notebook(lab), lab)
    assert findings, f"{cheat.name} ({cheat.attack}) was not found"
    wanted = cheat.blanks(lab) if cheat.scan_costs else ()
    if wanted == ():
        assert all(f.blanks == () for f in findings), findings
    else:
        assert covers(findings, wanted), findings
    if cheat.exact:  # a local trick costs its own blank, not every blank (a finding for review costs nothing)
        assert {f.blanks for f in findings} - {()} == {wanted} - {()}, findings
    assert all(f.reason.endswith(".") and f.reason[0].isupper() for f in findings)


EDGE_CASES = {  # an added cell -> the blanks charged by each finding (() flags without cost; [] no finding)
    "!pip install numpy": [()],
    "%pip install scipy": [()],
    "!cp ../../other-student/train-kf/train-kf.ipynb .": [None],
    "%config InlineBackend.figure_format = 'retina'": [],
    "%config InteractiveShell.ast_node_interactivity = 'all'": [None],
    "%load_ext autoreload\n%autoreload 2": [],
    "%time x = predict(np.zeros(2), np.eye(2), np.eye(2), np.eye(2))": [],
    "%time import solutions.train_kf.reference": [None],
    "import os\nos.environ['OMP_NUM_THREADS'] = '1'": [()],
    "import sys\nsys.setrecursionlimit(5000)": [],
    "plt.rcParams['figure.figsize'] = (8, 4)": [],
    "class Vector:\n    def __sub__(self, other):\n        return self\n": [],
    # IPython.display: rich output is allowed; the rest of IPython, folder listings and file reads are not
    "from IPython.display import display, Markdown\ndisplay(Markdown(f'RMSE = {1.0:.2f} m'))": [],
    "from IPython import display\ndisplay.display(display.Math(r'\\hat x'))": [],
    "import IPython.display\nIPython.display.display(1)": [None],
    "import IPython.display as ipd\nipd.FileLinks('.')": [None],
    "from IPython.display import FileLinks": [None],
    "from IPython.display import *": [None],
    "from IPython.display import Code\nCode(filename='/etc/passwd')": [None],
    "from IPython.display import Markdown\nMarkdown('../../other-student/train-kf/answers.md')": [None],
    "from IPython.display import Markdown\ntext = 'x'\nMarkdown(text)": [()],
    # globals(), vars(), locals(): their names may be looked at, their values (__builtins__ among them) not
    "print(len(globals()))": [],
    "print(sorted(globals()), 'np' in globals(), globals()['np'], list(globals().keys()))": [],
    "for name in globals():\n    print(name)": [],
    "globals()['np'] = None": [None],
    "globals()['__builtins__'].exec('1')": [None],
    "vars()['__builtins__']": [None],
    "locals()['__builtins__']": [None],
    "key = '__buil' + 'tins__'\nglobals()[key]": [None],
    "namespace = globals()\nnamespace['__builtins__']": [None],
    "for key, value in globals().items():\n    pass": [None],
    "globals().update(np=None)": [None],
    "globals().setdefault('np', None)": [None],
    # honest habits that a fairness review found costing every blank, in 9ce2242: a value by a public
    # name, a function's own locals, and the student's own object walked by name (review, no cost)
    "print(globals().get('x_f'))": [],
    "def show():\n    x = 1\n    for name, value in locals().items():\n        print(name, value)\n": [],
    "class Result:\n    pass\nresult = Result()\nfor name in ['rmse', 'nees']:\n    print(getattr(result, name, None))": [],
    "globals().get('__builtins__')": [None],
    "locals().items()": [None],
    # a computed attribute name on a module, a call's result or a builtin: print's __self__ is the builtins module
    "name = '__se' + 'lf__'\ngetattr(print, name)": [None],
    "setattr(np, 'file'.join('__'), 'x')": [None],
    "def check_close(*args, **kwargs):\n    pass\n": [()],
    "print('There are two solutions.')": [],
    "np.save('../../../gradebook.npy', np.zeros(1))": [None],
    "x = open(name).read()": [None],
    "fig, ax = plt.subplots()\nfig.savefig(f'figure_{1}.png')": [],
    # routes of issue 29's adversarial review (helper-53), each unflagged on 4813b9a: a method of the
    # builtin's name shadowed it everywhere; aliases, from-imports and re-exported modules hid the module;
    # some readers were not checked; getattr on an alias of a builtin passed as the student's own object
    "class T:\n    def exec(self):\n        pass\nexec('1')": [None],
    "class T:\n    def open(self):\n        pass\nopen('/etc/shadow')": [None],
    "from os import chmod\nchmod('/etc/shadow', 0o644)": [None],
    "from os import getxattr\ngetxattr('/work/x', 'user.k')": [None],
    "o = open\no('/work/solutions/x.py').read()": [None],
    "def f(o=open):\n    return o('/etc/shadow').read()": [None],
    "x = sys\nx.modules": [None],
    "q = os\nq.system('ls')": [None],
    "np.os.system('ls')": [None],
    "import io\nio.FileIO('/etc/shadow')": [None],
    "from scipy.io import loadmat\nloadmat('/etc/passwd')": [None],
    "plt.imread('../../other/x.png')": [None],
    "np.lib.format.open_memmap('/tmp/x.npy')": [None],
    "p = print\nname = '__se' + 'lf__'\ngetattr(p, name)": [None],
    # routes of the re-attack (helper-54), unflagged on c7463c6: a definition after the use, or deleted;
    # code in a pickle; builtins reached through a module that holds it; getattr handed to another function
    "exec('1')\ndef exec(*a):\n    pass": [None],
    "def exec(*a):\n    pass\ndel exec\nexec('1')": [None],
    "def helper(c):\n    exec(c)\nhelper('1')\ndef exec(*a):\n    pass": [None],
    "g = globals()\ng['__builtins__']\ndef globals():\n    return {}": [None],
    "import pickle\npickle.loads(b'x')": [None],
    "np.core.numeric.builtins.exec('1')": [None],
    "import pydoc\npydoc.locate('os.system')": [None],
    "import operator\nname = 'o' + 's'\noperator.attrgetter(name)(np)": [None],
    # the third review (helper-55): more runners of text, and honest uses that the second round's rules cost
    "import cProfile\ncProfile.run('1')": [None],
    "import pdb\npdb.run('1')": [None],
    "import typing\ntyping.get_type_hints(object)": [None],
    "np.ctypeslib.ctypes.pythonapi": [None],
    "import _pickle\n_pickle.loads(b'x')": [None],
    "import timeit\ncode = bytes.fromhex('31').decode()\ntimeit.timeit(code, number=1)": [None],
    "import timeit\ntimeit.timeit('1+1', number=3)": [()],
    "import timeit\ntimeit.timeit(lambda: 1, number=3)": [],
    "import pickle\nwith open('results.pkl', 'wb') as f:\n    pickle.dump({'a': 1}, f)\nwith open('results.pkl', 'rb') as f:\n    r = pickle.load(f)": [()],
    "import operator\nbest = min([1, 2], key=operator.attrgetter('real'))": [],
    "import operator\noperator.attrgetter('os.system')(np)('ls')": [None],
    "import functools\nfunctools.reduce(getattr, ['os', 'system'], np)": [None],
    "object.__getattribute__(np, 'os')": [None],
    # the fourth round (stop 46): honest code that cost every blank, though only data reaches the grader
    "class Run:\n    def __init__(self, rmse):\n        self.rmse = rmse\n    def __lt__(self, other):\n"
    "        return self.rmse < other.rmse\nprint(sorted([Run(2.0), Run(1.0)])[0].rmse)": [()],
    "class Bag(dict):\n    def __getattr__(self, key):\n        return self[key]\nprint(Bag(a=1).a)": [()],
    "for name in ('mean', 'median'):\n    print(name, getattr(np, name)([1.0, 2.0]))": [],
    "stats = {f: getattr(np, f) for f in ['min', 'max']}": [],
    "import io\nprint(np.loadtxt(io.StringIO('1 2\\n3 4')))": [],
    "from io import StringIO\nprint(np.genfromtxt(StringIO('1,2'), delimiter=','))": [],
    # and the same shapes that still cost: a name among the choices reaches a module, or is bound otherwise
    "for name in ('mean', 'os'):\n    getattr(np, name)": [None],
    "for name in ('mean', 'median'):\n    name = name.replace('m', 'o')\n    getattr(np, name)": [None],
    "for name in ('me' + 'an', 'o' + 's'):\n    getattr(np, name)": [None],
    "for name in names:\n    getattr(np, name)": [None],
    "import io\nnp.loadtxt(io.StringIO(open('/etc/passwd').read()))": [None],
    "getattr(np, 'os').system('ls')": [None],
    "x = getattr(np, 'o' + 's')\nx.system('ls')": [None],
    "for name in ('os',):\n    getattr(np, name).system('ls')": [None],
    "x = np.os\nx.listdir('/')": [None],
    "for name in ('allclose', 'isclose'):\n    setattr(np, name, lambda *a, **k: True)": [None],
    "solve = np.linalg.solve\nrng = np.random.default_rng(1)\nprint(solve(np.eye(2), rng.normal(size=2)))": [],
    # the fourth review (helper-56): a file's name held in a name, or passed to the notebook's own
    # function, cost every blank (an honest solved notebook that saved its figure scored 0/20)
    "import matplotlib.pyplot as plt\nout = 'track.png'\nplt.plot([0, 1], [0, 1])\nplt.savefig(out)": [],
    "name = 'results.csv'\nwith open(name, 'w') as f:\n    f.write('a')\nwith open(name) as f:\n    print(f.read())": [],
    "fname = 'areas.txt'\nnp.savetxt(fname, np.ones(3))": [],
    "from pathlib import Path\nnotes = Path('notes.txt')\nnotes.write_text('hi')": [],
    "from pathlib import Path\nfolder = Path('out')\nfolder.mkdir(exist_ok=True)\n(folder / 'a.txt').write_text('x')": [],
    "def save(rows, path):\n    with open(path, 'w') as f:\n        f.write(str(rows))\nsave([1, 2], 'rows.txt')\n"
    "save([3], path='more.txt')": [],
    "def save(rows, path='rows.txt'):\n    open(path, 'w').write(str(rows))\nsave([1])": [],
    # and the same shapes that still cost: the value leaves the folder, is bound twice, or is not known
    "where = '/etc/passwd'\nopen(where).read()": [None],
    "where = 'a.txt'\nwhere = '/etc/passwd'\nopen(where).read()": [None],
    "def save(rows, path):\n    open(path, 'w').write(str(rows))\nsave([1], input())": [None],
    "def save(rows, path):\n    open(path, 'w').write(str(rows))\nalias = save\nalias([1], '/etc/x')": [None],
    "from pathlib import Path\nbase = Path('/work')\n(base / 'x').read_text()": [None],
    # the fourth review (helper-56): pickle.loads of bytes in the cell ran builtins.exec at no cost (a blank
    # notebook scored 20/20 without the sandbox); bytes that read as such a pickle cost wherever they go
    "import pickle\nexec_in_a_pickle = b'cbuiltins\\nexec\\n(Vprint(1)\\ntR.'\nopen('p.pkl', 'wb').write(exec_in_a_pickle)\n"
    "pickle.load(open('p.pkl', 'rb'))": [(), None],
    "import marshal\nmarshal.loads(b'x')": [None],
    "data = b'\\x80\\x04K\\x01.'\nprint(data)": [],
    # and what stays honest: a nested function of a builtin's name is its own, an alias of print is print
    "def f():\n    def open(x):\n        return x\n    return open(1)": [],
    "log = print\nlog('RMSE', 1.0)": [],
    "def g(x, fn=print):\n    fn(x)": [],
    "def vars():\n    return {}\nprint(vars())": [],
    "print(sorted([3, 1], key=len))": [],
}


@pytest.mark.parametrize("source", EDGE_CASES)
def test_static_scan_edge_cases(source):
    nb = submissions.solved(TRAIN)
    index = next(i for i, c in enumerate(nb.cells) if cells.meta(c).get("grade_id") == "setup") + 1
    nb.cells.insert(index, nbformat.v4.new_code_cell(source))
    found = scan.static_findings(nb, TRAIN)
    assert sorted({f.blanks for f in found}, key=repr) == EDGE_CASES[source], found


NOT_STATIC = [(lab, cheat) for lab in LABS for cheat in cheats.catalogue(lab) if cheats.STATIC not in cheat.caught_by]


@pytest.mark.parametrize("lab, cheat", NOT_STATIC, ids=[f"{lab.id}-{cheat.name}" for lab, cheat in NOT_STATIC])
def test_static_scan_is_silent_where_another_defence_works(lab, cheat):
    """Overwritten test cells, hard-coded visible cases and the aliased patch are not static findings."""
    assert scan.static_findings(cheat.notebook(lab), lab) == []


# -- hard-coded visible cases -----------------------------------------------------------------------

def test_hard_coded_visible_cases_pass_the_visible_checks_and_fail_the_hidden_tests():
    from solutions.train_kf.hidden_tests import check_process_noise

    nb = cheats.get("hardcode-visible").notebook(TRAIN)
    namespace: dict = {}
    setup = next(c for c in nb.cells if cells.meta(c).get("grade_id") == "setup")
    exec("\n".join(line for line in setup.source.splitlines() if not line.startswith("%")), namespace)
    answer = next(c for c in nb.cells if cells.meta(c).get("grade_id") == "process_noise")
    exec(answer.source, namespace)
    visible = next(c for c in nb.cells if cells.meta(c).get("grade_id") == "check_process_noise")
    exec(visible.source, namespace)  # the visible checks pass
    with pytest.raises(AssertionError):
        check_process_noise(namespace["process_noise"])
    assert scan.static_findings(nb, TRAIN) == []


# -- the catalogue ----------------------------------------------------------------------------------

ATTACKS = {  # the threat model's attacks -> the cheats that represent them
    "import": "import-reference", "importlib": "importlib-reference", "__import__": "dunder-import-reference",
    "sys.modules": "sys-modules-reference", "sys.path edits": "sys-path-reference",
    "open() of the reference's files": "open-exec-reference", "exec of its source": "exec-obfuscated-import",
    "editing test cells": "edit-test-cell", "deleting test cells": "delete-test-cell",
    "input_transformers_cleanup": "input-transformer", "run_cell": "run-cell", "showtraceback": "showtraceback",
    "sys.excepthook": "excepthook", "events": "events", "errors swallowed": "custom-exc",
    "assert helpers": "patch-check-helpers", "numpy.testing and np.allclose": "patch-allclose",
    "__eq__ on returned objects": "eq-dunder", "hard-coded visible cases": "hardcode-visible",
    "writing to the gradebook": "gradebook-write", "writing to other students' folders": "other-student-write",
}


def test_the_catalogue_covers_every_attack_for_train_kf():
    names = {cheat.name for cheat in cheats.catalogue(TRAIN)}
    assert set(ATTACKS.values()) <= names
    for cheat in cheats.CHEATS:
        assert cheat.caught_by and cheat.caught_by <= {cheats.STATIC, cheats.GRADER, cheats.SANDBOX, cheats.OVERWRITE,
                                                       cheats.HIDDEN_TESTS}


@over_labs
def test_every_cheat_builds_a_valid_notebook(lab):
    for cheat in cheats.catalogue(lab):
        nb = cheat.notebook(lab)
        nbformat.validate(nb)
        assert nb != submissions.solved(lab), cheat.name


# -- what the scan may cost the grader ----------------------------------------------------------------
# A submission's code is parsed in the grader: IPython's transform of magics costs magic lines times
# lines (120 magics among 40,000 lines took 146 s), and a syntax tree hundreds of bytes per character
# (a 6 MB list literal took the grader to 9 GB). Before the caps, nothing bounded either.


def _with_added_cell(source: str) -> NotebookNode:
    nb = submissions.solved(TRAIN)
    nb.cells.insert(2, nbformat.v4.new_code_cell(source))
    return nb


def test_a_cell_larger_than_the_scan_reads_is_not_parsed_and_costs_every_blank(monkeypatch):
    source = "x = [" + "1, " * (scan.MAX_SCANNED_CELL_CHARS // 3) + "]\n"
    parsed = []
    monkeypatch.setattr(scan, "parse", lambda code: parsed.append(len(code)) or None)
    [finding] = scan.static_findings(_with_added_cell(source), TRAIN)
    assert finding.blanks is None and f"{len(source):,} characters" in finding.reason, finding
    assert max(parsed) < scan.MAX_SCANNED_CELL_CHARS


def test_the_scan_reads_at_most_its_cap_of_a_notebook(monkeypatch):
    monkeypatch.setattr(scan, "MAX_SCANNED_CHARS", 40_000)
    nb = submissions.solved(TRAIN)
    for k in range(4):
        nb.cells.insert(2, nbformat.v4.new_code_cell(f"y{k} = 1\n" * 2_000))  # 14,000 characters each
    [finding] = scan.static_findings(nb, TRAIN)  # one finding for all the cells it did not read
    assert finding.blanks is None and "it reads 40,000 in all" in finding.reason, finding
    assert "did not read 2 cells" in finding.reason, finding


def test_the_confined_scan_finds_what_the_scan_finds():
    from autograder.integrity.confined import confined_findings

    assert confined_findings(submissions.solved(TRAIN), TRAIN) == []
    assert confined_findings(honest_habits_notebook(), TRAIN) == []
    cheat = cheats.get("patch-allclose").notebook(TRAIN)
    assert confined_findings(cheat, TRAIN) == scan.static_findings(cheat, TRAIN) != []


def test_a_scan_over_its_cpu_time_is_stopped_and_costs_every_blank():
    """50 magics among 10,000 lines, under the size caps: 13 s of the grader's CPU before; here the
    child stops at 1 s and the grader spends none of it."""
    import resource
    import time

    from autograder.integrity.confined import confined_findings

    source = "".join(f"a{i} = %time 1\n" for i in range(50)) + "b = 1\n" * 10_000
    assert len(source) < scan.MAX_SCANNED_CELL_CHARS
    own, start = time.process_time(), time.monotonic()
    [finding] = confined_findings(_with_added_cell(source), TRAIN, cpu_seconds=1)
    assert finding.blanks is None and "ran out of its time" in finding.reason, finding
    assert time.process_time() - own < 1.0
    assert time.monotonic() - start < 60
    assert resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime > 0.5


def test_a_scan_over_its_memory_is_stopped_and_costs_every_blank():
    """A list literal under the size caps, whose syntax tree needs more than the child may grow: the
    grader does not grow (before, the tree grew and stayed in the grader's process, cached).

    Run in a fresh interpreter: a forked child may first fill memory that its parent freed but still
    maps, and a test worker that has graded classes holds tens of MB of it, so in the worker the 8 MiB
    cap was not reached and the scan finished (CI of stop 38)."""
    import subprocess
    import sys
    from pathlib import Path

    script = (
        "import json, resource\n"
        "from autograder.integrity.confined import confined_findings\n"
        "from test_integrity import TRAIN, _with_added_cell\n"
        "before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss\n"
        "[finding] = confined_findings(_with_added_cell('x = [' + '1,' * 45_000 + ']\\n'), TRAIN, memory_bytes=8 << 20)\n"
        "grown = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before\n"
        "print(json.dumps({'blanks': finding.blanks, 'reason': finding.reason, 'grown_kib': grown}))\n"
    )
    root = Path(__file__).resolve().parent.parent
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300,
                          env={**os.environ, "PYTHONPATH": f"{root}{os.pathsep}{root / 'tests'}"})
    assert done.returncode == 0, done.stderr
    finding = json.loads(done.stdout.splitlines()[-1])
    assert finding["blanks"] is None and "nothing checked" in finding["reason"], finding
    assert finding["grown_kib"] < 20_000

"""The cheating defences (autograder/integrity.py, autograder/integrity_monitor.py) against the
catalogue of hostile submissions (autograder/cheats.py) and the honest corpus.

- Static scan: no finding on any honest notebook (every lab's blank release, solved notebook and
  catalogued mistakes); every cheat it should catch is caught, charged to the right blanks.
- Runtime monitor: notebooks run with nbclient the way the grading executor runs them
  (INTEGRITY_SETUP silently first, then the cells, RUNTIME_PROBE after each graded test cell). No
  finding on any honest run; every runtime cheat is reported; the worst are refused outright.
- Edited and deleted test cells: the course's sanitize step (RestoreLabCells, then nbgrader's
  OverwriteCells) restores them, and the wrong blank still scores 0. Hard-coded visible cases: the hidden tests fail them.

Notebooks run three at a time in one event loop. Cheats run on a trimmed notebook (set-up,
answers, graded tests and student-added cells); honest solved notebooks run whole. Every lab's
catalogued mistakes pass the static scan; train-kf's also run, all in one kernel, under the
monitor (the others' hidden tests are slow, and a mistake changes arithmetic, not what the
monitor watches).
"""

from __future__ import annotations

import ast
import asyncio
import copy
import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient
from nbformat import NotebookNode
from nbgrader.utils import determine_grade, setenv

from autograder import cells, cheats, integrity, submissions
from autograder.integrity import INTEGRITY_SETUP, PROBE_NAME, RUNTIME_PROBE, Finding, runtime_findings
from autograder.labs import ROOT, Lab, get_lab
from autograder.mistakes import catalogue as mistakes
from course.checks import GRADING
from over_labs import LABS, over_labs

TRAIN = get_lab("train-kf")
PARALLEL = 3
CELL_TIMEOUT = 180
OTHER_LAB_CHEATS = ("patch-allclose", "open-exec-reference", "showtraceback", "gc-reference")
"""Runtime cheats also run on the other labs (one each, in turn), to show the catalogue works beyond
train-kf."""
OTHER_LABS = [lab for lab in LABS if lab != TRAIN]
OTHER_LAB_CASES = [(lab, OTHER_LAB_CHEATS[i % len(OTHER_LAB_CHEATS)]) for i, lab in enumerate(OTHER_LABS)]


# -- running notebooks as the grader does ------------------------------------------------------------

@dataclass
class Run:
    nb: NotebookNode
    probes: list[tuple[str, list[Finding]]] = field(default_factory=list)
    """(test cell grade_id, runtime findings) for the probe after each graded test cell, then ("", ...)."""
    scores: dict[str, float] = field(default_factory=dict)
    """grade_id -> nbgrader's score of each graded test cell (the last one, for repeated ids)."""
    names_before: list[str] = field(default_factory=list)
    names_after: list[str] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def findings(self) -> list[Finding]:
        """Every runtime finding, deduplicated (the reports are cumulative)."""
        seen, out = set(), []
        for _, found in self.probes:
            for finding in found:
                if (finding.reason, finding.blanks) not in seen:
                    seen.add((finding.reason, finding.blanks))
                    out.append(finding)
        return out


def trimmed(nb: NotebookNode, lab: Lab) -> NotebookNode:
    """The set-up cell, the answer cells, the graded test cells and any cell the source does not have."""
    known = {cells.grade_id(c): c for c in cells.read(lab.source_notebook).cells if cells.meta(c).get("grade_id")}
    nb = copy.deepcopy(nb)
    keep = []
    for cell in nb.cells:
        if cell.cell_type != "code":
            continue
        original = known.get(cells.meta(cell).get("grade_id"))
        if original is None or cells.is_answer(original) or cells.is_autograded_test(original) or (
                cells.grade_id(original) == "setup"):
            keep.append(cell)
    nb.cells = keep
    return nb


async def _silent(client: NotebookClient, code: str, expressions: dict | None = None) -> dict:
    msg_id = client.kc.execute(code, silent=True, store_history=False, user_expressions=expressions or {})
    reply = await client.async_wait_for_reply(msg_id)
    return reply["content"]


async def _probe(client: NotebookClient, cell_id: str) -> list[Finding]:
    content = await _silent(client, "", {PROBE_NAME: RUNTIME_PROBE})
    return runtime_findings(content["user_expressions"][PROBE_NAME], cell_id)


async def _execute(nb: NotebookNode, lab: Lab, course: Path) -> Run:
    """Run ``nb`` from ``course/submitted/student/<lab>`` with the integrity setup and probes."""
    cwd = course / "submitted" / "student" / lab.id
    cwd.mkdir(parents=True, exist_ok=True)
    run = Run(copy.deepcopy(nb))
    start = time.monotonic()
    client = NotebookClient(run.nb, kernel_name="python3", allow_errors=True, timeout=CELL_TIMEOUT,
                            resources={"metadata": {"path": str(cwd)}},
                            extra_arguments=["--HistoryManager.hist_file=:memory:", "--IPKernelApp.log_level=ERROR"])
    names = {PROBE_NAME: "sorted(globals())"}

    def listed_names(content: dict) -> list[str]:
        value = content["user_expressions"][PROBE_NAME]
        return ast.literal_eval(value["data"]["text/plain"]) if value.get("status") == "ok" else ["<error>"]

    async with client.async_setup_kernel():
        setup = await _silent(client, INTEGRITY_SETUP)
        assert setup["status"] == "ok", setup
        for index, cell in enumerate(run.nb.cells):
            if cell.cell_type != "code":
                continue
            await client.async_execute_cell(cell, index, store_history=True)
            if cells.is_autograded_test(cell):
                if not run.names_before:
                    listed = await _silent(client, "", names)
                    run.names_before = listed_names(listed)
                run.probes.append((cells.grade_id(cell), await _probe(client, cells.grade_id(cell))))
                if not run.names_after:
                    listed = await _silent(client, "", names)
                    run.names_after = listed_names(listed)
        run.probes.append(("", await _probe(client, "")))
    for cell in run.nb.cells:
        if cells.is_autograded_test(cell):
            run.scores[cells.grade_id(cell)] = determine_grade(cell)[0]
    run.seconds = time.monotonic() - start
    return run


def execute_all(jobs: dict[str, tuple[NotebookNode, Lab, Path]]) -> dict[str, Run]:
    """Run every job, ``PARALLEL`` kernels at a time, as ``nbgrader autograde`` runs its kernels
    (NBGRADER_EXECUTION: course.checks then installs no hooks, and validate() does nothing)."""
    async def main():
        gate = asyncio.Semaphore(PARALLEL)

        async def one(name, nb, lab, course):
            async with gate:
                return name, await _execute(nb, lab, course)

        return dict(await asyncio.gather(*(one(name, *job) for name, job in jobs.items())))

    with setenv(NBGRADER_EXECUTION=GRADING):
        return asyncio.run(main())


HONEST_HABITS = '''%timeit -n 3 -r 1 predict(np.zeros(2), np.eye(2), np.eye(2), np.eye(2))
import functools
import json
import math
import traceback
import warnings
from dataclasses import dataclass

import scipy.optimize


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
'''
"""Things honest students do that the defences must not mind: magics, imports, a dataclass (which has
__eq__), a traceback printed, files written and read in their own folder, a figure saved."""


def honest_habits_notebook(grader_snippets: bool = False) -> NotebookNode:
    """The solved train-kf notebook with a cell of honest habits, and a local try/except in predict;
    with ``grader_snippets``, INTEGRITY_SETUP and RUNTIME_PROBE as two last cells."""
    nb = submissions.solved(TRAIN)
    index = next(i for i, c in enumerate(nb.cells) if cells.meta(c).get("grade_id") == "run_filter") + 1
    nb.cells.insert(index, nbformat.v4.new_code_cell(HONEST_HABITS))
    answer = next(c for c in nb.cells if cells.meta(c).get("grade_id") == "predict")
    answer.source = answer.source.replace("    x_f = A @ x\n", "    try:\n        x_f = A @ x\n    except ValueError as "
                                          "error:\n        raise ValueError(f'bad shapes: {error}') from error\n")
    assert "try:" in answer.source
    if grader_snippets:  # run as ordinary cells, they must print nothing
        nb.cells += [nbformat.v4.new_code_cell(INTEGRITY_SETUP), nbformat.v4.new_code_cell(RUNTIME_PROBE + ";")]
    return nb


def graded_form(nb: NotebookNode, lab: Lab) -> NotebookNode:
    """What nbgrader runs for an honest notebook: every locked cell (test cells with their hidden
    tests) as in the source notebook. The same as the sanitize step for a notebook that kept its
    cells, without making a gradebook."""
    locked = {cells.grade_id(c): c.source for c in cells.read(lab.source_notebook).cells
              if cells.meta(c).get("grade_id") and not cells.is_answer(c)}
    nb = copy.deepcopy(nb)
    for cell in nb.cells:
        if cells.meta(cell).get("grade_id") in locked:
            cell.source = locked[cells.grade_id(cell)]
    return nb


def mistakes_notebook(lab: Lab) -> NotebookNode:
    """The trimmed solved notebook, then for each catalogued mistake: the mistaken answer, its graded
    test cell (with its hidden tests) again, and the model answer back. One kernel grades every
    mistake of the lab."""
    source = cells.read(lab.source_notebook)
    nb = trimmed(source, lab)
    answers = {cells.grade_id(c): c for c in nb.cells if cells.is_code_answer(c)}
    for cell in answers.values():
        cell.source = cells.model_answer(cell)
    tests = {cells.grade_id(c): c for c in source.cells if cells.is_autograded_test(c)}
    for mistake in mistakes(lab):
        wrong = nbformat.v4.new_code_cell(mistake.apply(answers[mistake.blank].source))
        nb.cells += [wrong, copy.deepcopy(tests[f"test_{mistake.blank}"]),
                     nbformat.v4.new_code_cell(answers[mistake.blank].source)]
    return nb


# -- nbgrader's sanitizing step ----------------------------------------------------------------------

def sanitized(nb: NotebookNode, lab: Lab, course: Path) -> NotebookNode:
    """``nb`` after the course's sanitize preprocessors (RestoreLabCells, OverwriteCells, ...), run
    against a gradebook made by nbgrader's generate_assignment, as ``nbgrader autograde`` runs them."""
    from nbgrader.converters import GenerateAssignment
    from nbgrader.coursedir import CourseDirectory
    from nbgrader.utils import capture_log
    from traitlets.config.loader import PyFileConfigLoader

    config = PyFileConfigLoader("nbgrader_config.py", path=str(ROOT)).load_config()
    config.CourseDirectory.root = str(course)
    config.CourseDirectory.source_directory = str(ROOT / "source")
    db_url = f"sqlite:///{course / 'gradebook.db'}"
    config.CourseDirectory.db_url = db_url
    course.mkdir(parents=True, exist_ok=True)
    if not (course / "gradebook.db").exists():
        coursedir = CourseDirectory(config=config)
        coursedir.assignment_id = lab.id
        app = GenerateAssignment(coursedir=coursedir, config=config)
        app.force = True
        result = capture_log(app)
        assert result["success"], result
    resources = {"nbgrader": {"notebook": lab.id, "assignment": lab.id, "student": "student", "db_url": db_url,
                              "course_id": config.CourseDirectory.course_id}}
    nb = copy.deepcopy(nb)
    for preprocessor in config.Autograde.sanitize_preprocessors:
        nb, resources = preprocessor(config=config).preprocess(nb, resources)
    return nb


# -- fixtures ---------------------------------------------------------------------------------------

RUNTIME_CHEATS = [c for c in cheats.catalogue(TRAIN) if cheats.RUNTIME in c.caught_by]
OVERWRITE_CHEATS = [c for c in cheats.catalogue(TRAIN) if cheats.OVERWRITE in c.caught_by]


@pytest.fixture(scope="module")
def course(tmp_path_factory) -> Path:
    """A course folder: its gradebook, and another student's folder the cheats try to reach."""
    course = tmp_path_factory.mktemp("course")
    other = course / "submitted" / "other-student" / TRAIN.module
    other.mkdir(parents=True)
    (other / "train-kf.ipynb").write_text("{}")
    return course


@pytest.fixture(scope="module")
def runs(course: Path) -> dict[str, Run]:
    """Every notebook the runtime tests need, executed once."""
    jobs: dict[str, tuple[NotebookNode, Lab, Path]] = {}
    for lab in LABS:
        jobs[f"solved/{lab.id}"] = (graded_form(submissions.solved(lab), lab), lab, course)
        blank = graded_form(cells.read(lab.release_notebook), lab)
        jobs[f"blank/{lab.id}"] = (blank if lab == TRAIN else trimmed(blank, lab), lab, course)
    jobs[f"mistakes/{TRAIN.id}"] = (mistakes_notebook(TRAIN), TRAIN, course)
    jobs["habits/train-kf"] = (sanitized(honest_habits_notebook(grader_snippets=True), TRAIN, course), TRAIN, course)
    for lab, name in OTHER_LAB_CASES:
        nb = graded_form(cheats.get(name).notebook(lab), lab)
        jobs[f"cheat/{name}/{lab.id}"] = (trimmed(nb, lab), lab, course)
    for cheat in RUNTIME_CHEATS:
        nb = sanitized(cheat.notebook(TRAIN), TRAIN, course)
        jobs[f"cheat/{cheat.name}/{TRAIN.id}"] = (trimmed(nb, TRAIN), TRAIN, course)
    broken = {}
    for cheat in OVERWRITE_CHEATS:
        try:
            restored = sanitized(cheat.notebook(TRAIN), TRAIN, course)
        except Exception as error:  # nbgrader itself fails on some edits; the test says which
            broken[f"overwrite/{cheat.name}"] = error
            continue
        jobs[f"overwrite/{cheat.name}"] = (trimmed(restored, TRAIN), TRAIN, course)
    before = (course / "gradebook.db").read_bytes()
    results = execute_all(jobs)
    results["gradebook-bytes"] = (before, (course / "gradebook.db").read_bytes())  # type: ignore[assignment]
    results.update(broken)  # type: ignore[arg-type]
    return results


def covers(findings: list[Finding], blanks: tuple[str, ...] | None) -> bool:
    """Whether the findings charge at least ``blanks`` (None: every blank)."""
    if any(f.blanks is None for f in findings):
        return True
    charged = {b for f in findings for b in f.blanks}
    return blanks is not None and set(blanks) <= charged


# -- the report's format ----------------------------------------------------------------------------

def test_runtime_findings_read_the_report_in_every_form():
    report = json.dumps([integrity.HEADER, {"reason": "numpy.allclose was replaced.", "blanks": None},
                         {"reason": "Walks the call stack.", "blanks": ["predict"]}])
    want = [Finding("test_predict", None, "numpy.allclose was replaced."),
            Finding("test_predict", ("predict",), "Walks the call stack.")]
    assert runtime_findings(report, "test_predict") == want
    assert runtime_findings(repr(report), "test_predict") == want
    assert runtime_findings({"status": "ok", "data": {"text/plain": repr(report)}}, "test_predict") == want
    assert runtime_findings(repr(json.dumps([integrity.HEADER])), "test_x") == []


@pytest.mark.parametrize("result", ["", "''", "'[]'", "'not json'", repr(json.dumps([{"monitor": "forged"}])),
                                    {"status": "error", "ename": "NameError", "evalue": "__import__"}])
def test_a_missing_or_forged_report_is_a_finding(result):
    [finding] = runtime_findings(result, "test_predict")
    assert finding.blanks is None and finding.cell == "test_predict"


# -- the honest corpus ------------------------------------------------------------------------------

def full_marks(lab: Lab) -> dict[str, float]:
    """grade_id -> points of every graded test cell, from the source notebook's metadata."""
    return {cells.grade_id(c): cells.meta(c)["points"] for c in cells.read(lab.source_notebook).cells
            if cells.is_autograded_test(c)}


@over_labs
def test_static_scan_flags_no_honest_notebook(lab):
    notebooks = {"blank release": cells.read(lab.release_notebook), "solved": submissions.solved(lab)}
    notebooks |= {f"mistake {m.blank}/{m.slug}": submissions.with_mistake(lab, m) for m in mistakes(lab)}
    flagged = {name: found for name, nb in notebooks.items() if (found := integrity.static_findings(nb, lab))}
    assert not flagged
    assert len(notebooks) == 2 + len(mistakes(lab))


@over_labs
def test_runtime_monitor_flags_no_honest_run(runs, lab):
    for kind in ("solved", "blank", "mistakes"):
        if f"{kind}/{lab.id}" not in runs:
            continue  # every lab's mistakes pass the static scan; train-kf's also run under the monitor
        run = runs[f"{kind}/{lab.id}"]
        assert len(run.probes) > 1, f"{kind}: no graded test cell ran"
        assert run.findings == [], f"{kind} notebook of {lab.id}: {run.findings}"
    solved, blank = runs[f"solved/{lab.id}"], runs[f"blank/{lab.id}"]
    assert solved.scores == full_marks(lab), "the solved notebook, run under the monitor, must score full marks"
    assert all(score == 0 for score in blank.scores.values()), blank.scores
    if lab == TRAIN:
        assert len(runs[f"mistakes/{lab.id}"].probes) > len(mistakes(lab)), "the mistakes notebook graded too little"


def test_honest_habits_are_not_flagged(runs):
    nb = honest_habits_notebook()
    assert integrity.static_findings(nb, TRAIN) == []
    run = runs["habits/train-kf"]
    assert run.findings == []
    assert run.scores == full_marks(TRAIN), "honest habits must keep full marks"
    outputs = [o for c in run.nb.cells if c.source.startswith("%timeit") for o in c.outputs]
    assert any("per loop" in o.get("text", "") for o in outputs), outputs  # the honest cell ran


def test_setup_and_probe_print_nothing_and_leave_no_names(runs):
    run = runs[f"solved/{TRAIN.id}"]
    assert run.names_before and run.names_before == run.names_after
    for cell in run.nb.cells:  # the silent setup and probes add no output to any cell
        for output in cell.get("outputs", []):
            assert "integrity" not in json.dumps(output)
    habits = runs["habits/train-kf"]
    setup, probe = habits.nb.cells[-2:]
    assert setup.source == INTEGRITY_SETUP and setup.outputs == []
    assert probe.source.startswith(RUNTIME_PROBE) and probe.outputs == []


# -- static scan of the cheats ----------------------------------------------------------------------

STATIC_CASES = [(lab, cheat) for lab in LABS for cheat in cheats.catalogue(lab) if cheats.STATIC in cheat.caught_by]


@pytest.mark.parametrize("lab, cheat", STATIC_CASES, ids=[f"{lab.id}-{cheat.name}" for lab, cheat in STATIC_CASES])
def test_static_scan_catches_cheat(lab, cheat):
    findings = integrity.static_findings(cheat.notebook(lab), lab)
    assert findings, f"{cheat.name} ({cheat.attack}) was not found"
    wanted = cheat.blanks(lab)
    if wanted == ():
        assert all(f.blanks == () for f in findings), findings
    else:
        assert covers(findings, wanted), findings
    if cheat.exact:  # a local trick costs its own blank, not every blank
        assert {f.blanks for f in findings} == {wanted}, findings
    assert all(f.reason.endswith(".") and f.reason[0].isupper() for f in findings)


EDGE_CASES = {  # an added cell -> the blanks charged by each finding (() flags without cost; [] no finding)
    "!pip install numpy": [()],
    "%pip install scipy": [()],
    "!cp ../../other-student/train-kf/train-kf.ipynb .": [None],
    "%config InlineBackend.figure_format = 'retina'": [],
    "%config InteractiveShell.ast_node_interactivity = 'all'": [None],
    "%load_ext autoreload\n%autoreload 2": [],
    "%time x = predict(np.zeros(2), np.eye(2), np.eye(2), np.eye(2))": [],
    "%time import solutions.train_kf": [None],
    "import os\nos.environ['OMP_NUM_THREADS'] = '1'": [()],
    "import sys\nsys.setrecursionlimit(5000)": [],
    "plt.rcParams['figure.figsize'] = (8, 4)": [],
    "class Vector:\n    def __sub__(self, other):\n        return self\n": [],
    "def check_close(*args, **kwargs):\n    pass\n": [()],
    "print('There are two solutions.')": [],
    "np.save('../../../gradebook.npy', np.zeros(1))": [None],
    "x = open(name).read()": [None],
    "fig, ax = plt.subplots()\nfig.savefig(f'figure_{1}.png')": [],
}


@pytest.mark.parametrize("source", EDGE_CASES)
def test_static_scan_edge_cases(source):
    nb = submissions.solved(TRAIN)
    index = next(i for i, c in enumerate(nb.cells) if cells.meta(c).get("grade_id") == "setup") + 1
    nb.cells.insert(index, nbformat.v4.new_code_cell(source))
    found = integrity.static_findings(nb, TRAIN)
    assert sorted({f.blanks for f in found}, key=repr) == EDGE_CASES[source], found


NOT_STATIC = [(lab, cheat) for lab in LABS for cheat in cheats.catalogue(lab) if cheats.STATIC not in cheat.caught_by]


@pytest.mark.parametrize("lab, cheat", NOT_STATIC, ids=[f"{lab.id}-{cheat.name}" for lab, cheat in NOT_STATIC])
def test_static_scan_is_silent_where_another_defence_works(lab, cheat):
    """Overwritten test cells, hard-coded visible cases and the aliased patch are not static findings."""
    assert integrity.static_findings(cheat.notebook(lab), lab) == []


# -- runtime monitor on the cheats -----------------------------------------------------------------

@pytest.mark.parametrize("cheat", RUNTIME_CHEATS, ids=[c.name for c in RUNTIME_CHEATS])
def test_runtime_monitor_catches_cheat(runs, cheat):
    run = runs[f"cheat/{cheat.name}/{TRAIN.id}"]
    findings = run.findings
    assert findings, f"{cheat.name} ({cheat.attack}) was not reported"
    assert covers(findings, cheat.blanks(TRAIN)), findings
    if cheat.exact:
        assert {f.blanks for f in findings} == {cheat.blanks(TRAIN)}, findings
    first = next(cell for cell, found in run.probes if found)
    assert first.startswith("test_") or first == "", "findings carry the test cell after which they were found"


@pytest.mark.parametrize("lab, name", OTHER_LAB_CASES, ids=[f"{lab.id}-{name}" for lab, name in OTHER_LAB_CASES])
def test_runtime_monitor_catches_cheats_in_every_lab(runs, lab, name):
    cheat = cheats.get(name)
    findings = runs[f"cheat/{name}/{lab.id}"].findings
    assert findings and covers(findings, cheat.blanks(lab)), findings


WORKS_UNDETECTED = ("import-reference", "sys-path-reference", "exec-obfuscated-import", "patch-allclose", "alias-patch-allclose", "showtraceback", "input-transformer", "run-cell",
                    "events", "custom-exc", "ast-transformer", "array-frame-walk")


@pytest.mark.parametrize("name", WORKS_UNDETECTED)
def test_these_cheats_would_score_without_the_monitor(runs, name):
    """The wrong (or reference-copying) target blank passes its graded cell: only the findings stop it."""
    run = runs[f"cheat/{name}/{TRAIN.id}"]
    assert run.scores[f"test_{cheats.target(TRAIN)}"] > 0, run.scores
    assert run.findings


REFUSED = {"open-exec-reference": "PermissionError", "gc-reference": "PermissionError",
           "patch-check-helpers": "PermissionError", "gradebook-write": "PermissionError",
           "other-student-write": "PermissionError", "shell-command": "PermissionError"}


@pytest.mark.parametrize("name", sorted(REFUSED))
def test_the_monitor_refuses_the_worst_operations(runs, course, name):
    run = runs[f"cheat/{name}/{TRAIN.id}"]
    errors = [o for c in run.nb.cells for o in c.get("outputs", []) if o.output_type == "error"]
    assert any(o.ename == REFUSED[name] and "Not allowed during grading" in o.evalue for o in errors), errors
    assert run.scores[f"test_{cheats.target(TRAIN)}"] == 0 or cheats.get(name).games == "all", run.scores


def test_nothing_was_written_outside_the_submission(runs, course):
    before, after = runs["gradebook-bytes"]
    assert before == after
    assert not (course / "submitted" / "other-student" / TRAIN.module / "notes.txt").exists()
    copied = list((course / "submitted" / "student" / TRAIN.id).glob("*.ipynb"))
    assert copied == []


# -- test cells edited or deleted -------------------------------------------------------------------

@pytest.mark.parametrize("cheat", OVERWRITE_CHEATS, ids=[c.name for c in OVERWRITE_CHEATS])
def test_nbgrader_restores_test_cells_and_the_wrong_blank_scores_zero(runs, cheat):
    run = runs[f"overwrite/{cheat.name}"]
    # nbgrader 0.9.6 alone fails on a test cell retagged with an unknown grade_id (KeyError
    # 'grade_id'); RestoreLabCells drops such metadata first, so every one of these is graded.
    assert not isinstance(run, Exception), run
    blank = cheats.target(TRAIN)
    source = {cells.grade_id(c): c.source for c in cells.read(TRAIN.source_notebook).cells
              if cells.is_autograded_test(c)}
    restored = [c for c in run.nb.cells if cells.is_autograded_test(c) and cells.grade_id(c) == f"test_{blank}"]
    assert len(restored) == 1 and restored[0].source.endswith(source[f"test_{blank}"])
    ids = [c.id for c in run.nb.cells]
    assert len(ids) == len(set(ids)), "a restored cell shares its cell id with the student's copy"
    nbformat.validate(run.nb)
    assert set(run.scores) == set(source)
    assert run.scores[f"test_{blank}"] == 0
    assert all(score > 0 for cell, score in run.scores.items() if cell != f"test_{blank}"), run.scores
    assert run.findings == [] and integrity.static_findings(run.nb, TRAIN) == []


# -- hard-coded visible cases -----------------------------------------------------------------------

def test_hard_coded_visible_cases_pass_the_visible_checks_and_fail_the_hidden_tests():
    from autograder.hidden_tests.train_kf import check_process_noise

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
    assert integrity.static_findings(nb, TRAIN) == []


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
        assert cheat.caught_by and cheat.caught_by <= {cheats.STATIC, cheats.RUNTIME, cheats.OVERWRITE,
                                                       cheats.HIDDEN_TESTS}


@over_labs
def test_every_cheat_builds_a_valid_notebook(lab):
    for cheat in cheats.catalogue(lab):
        nb = cheat.notebook(lab)
        nbformat.validate(nb)
        assert nb != submissions.solved(lab), cheat.name


def test_the_runs_stay_fast(runs):
    """Measured cost of the monitor, printed for the record (pytest -s)."""
    timed = {name: round(run.seconds, 1) for name, run in runs.items() if isinstance(run, Run)}
    print(json.dumps(timed, indent=1))
    assert max(timed.values()) < CELL_TIMEOUT

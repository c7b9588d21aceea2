"""The cheating defences (autograder/integrity.py, autograder/integrity_monitor.py) against the
catalogue of hostile submissions (autograder/cheats.py) and the honest corpus.

- Static scan: no finding on any honest notebook (every lab's blank release, solved notebook and
  catalogued mistakes); every cheat it should catch is caught, charged to the right blanks.
- Runtime monitor: notebooks run with nbclient the way the grading executor runs them
  (INTEGRITY_SETUP silently first, then the cells, RUNTIME_PROBE after each graded test cell). No
  finding on any honest run; every runtime cheat is reported; the worst are refused outright.
- Edited and deleted test cells: the course's sanitize step (RestoreLabCells, then nbgrader's
  OverwriteCells) restores them, and the wrong blank still scores 0. Hard-coded visible cases: the hidden tests fail them.

Notebooks run two at a time in one event loop. Cheats run on a trimmed notebook (set-up, answers,
graded tests and student-added cells); honest solved and blank notebooks run whole.
"""

from __future__ import annotations

import asyncio
import copy
import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient
from nbformat import NotebookNode
from nbgrader.utils import determine_grade

from autograder import cells, cheats, integrity, submissions
from autograder.integrity import INTEGRITY_SETUP, PROBE_NAME, RUNTIME_PROBE, Finding, runtime_findings
from autograder.labs import ROOT, Lab, all_labs, get_lab
from autograder.mistakes import catalogue as mistakes
from over_labs import LABS, over_labs

TRAIN = get_lab("train-kf")
PARALLEL = 2
CELL_TIMEOUT = 180
OTHER_LAB_CHEATS = ("patch-allclose", "open-exec-reference", "showtraceback")
"""Runtime cheats also run on every other lab, to show the catalogue works beyond train-kf."""


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
                    run.names_before = eval(listed["user_expressions"][PROBE_NAME]["data"]["text/plain"])
                run.probes.append((cells.grade_id(cell), await _probe(client, cells.grade_id(cell))))
                if not run.names_after:
                    listed = await _silent(client, "", names)
                    run.names_after = eval(listed["user_expressions"][PROBE_NAME]["data"]["text/plain"])
        run.probes.append(("", await _probe(client, "")))
    for cell in run.nb.cells:
        if cells.is_autograded_test(cell):
            run.scores[cells.grade_id(cell)] = determine_grade(cell)[0]
    run.seconds = time.monotonic() - start
    return run


def execute_all(jobs: dict[str, tuple[NotebookNode, Lab, Path]]) -> dict[str, Run]:
    """Run every job, ``PARALLEL`` kernels at a time."""
    async def main():
        gate = asyncio.Semaphore(PARALLEL)

        async def one(name, nb, lab, course):
            async with gate:
                return name, await _execute(nb, lab, course)

        return dict(await asyncio.gather(*(one(name, *job) for name, job in jobs.items())))

    return asyncio.run(main())


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
        graded = course / lab.id
        jobs[f"solved/{lab.id}"] = (sanitized(submissions.solved(lab), lab, graded), lab, graded)
        jobs[f"blank/{lab.id}"] = (sanitized(cells.read(lab.release_notebook), lab, graded), lab, graded)
        jobs[f"mistakes/{lab.id}"] = (mistakes_notebook(lab), lab, graded)
        if lab != TRAIN:
            for name in OTHER_LAB_CHEATS:
                nb = sanitized(cheats.get(name).notebook(lab), lab, graded)
                jobs[f"cheat/{name}/{lab.id}"] = (trimmed(nb, lab), lab, graded)
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
        run = runs[f"{kind}/{lab.id}"]
        assert len(run.probes) > 1, f"{kind}: no graded test cell ran"
        assert run.findings == [], f"{kind} notebook of {lab.id}: {run.findings}"
    solved, blank = runs[f"solved/{lab.id}"], runs[f"blank/{lab.id}"]
    assert all(score > 0 for score in solved.scores.values()), solved.scores
    assert all(score == 0 for score in blank.scores.values()), blank.scores
    graded_mistakes = [score for cell, score in runs[f"mistakes/{lab.id}"].scores.items()]
    assert graded_mistakes, "the mistakes notebook graded nothing"


def test_setup_and_probe_print_nothing_and_leave_no_names(runs):
    run = runs[f"solved/{TRAIN.id}"]
    assert run.names_before and run.names_before == run.names_after
    for cell in run.nb.cells:  # the silent setup and probes add no output to any cell
        for output in cell.get("outputs", []):
            assert "integrity" not in json.dumps(output)


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


@pytest.mark.parametrize("name", OTHER_LAB_CHEATS)
@pytest.mark.parametrize("lab", [lab for lab in LABS if lab != TRAIN], ids=lambda lab: lab.id)
def test_runtime_monitor_catches_cheats_in_every_lab(runs, name, lab):
    cheat = cheats.get(name)
    findings = runs[f"cheat/{name}/{lab.id}"].findings
    assert findings and covers(findings, cheat.blanks(lab)), findings


WORKS_UNDETECTED = ("patch-allclose", "alias-patch-allclose", "showtraceback", "input-transformer", "run-cell",
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
    if isinstance(run, Exception):
        # nbgrader 0.9.6's OverwriteCells deletes an unknown grade_id but keeps the cell's nbgrader
        # metadata, then add_missing_task_cells fails on it (KeyError 'grade_id'): the submission
        # is not graded at all. A sanitize step that drops the nbgrader metadata of cells with
        # unknown grade_ids, before OverwriteCells, fixes it.
        pytest.xfail(f"nbgrader cannot sanitize this submission: {type(run).__name__}: {run}")
    blank = cheats.target(TRAIN)
    source = {cells.grade_id(c): c.source for c in cells.read(TRAIN.source_notebook).cells
              if cells.is_autograded_test(c)}
    restored = [c for c in run.nb.cells if cells.is_autograded_test(c) and cells.grade_id(c) == f"test_{blank}"]
    assert len(restored) == 1 and restored[0].source.endswith(source[f"test_{blank}"])
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

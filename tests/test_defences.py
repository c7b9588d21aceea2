"""Cheating gains nothing whether or not the scan finds it: submissions run through the grading
execute step alone (GradingExecute with the course's configuration: hidden tests compared in the
grader's process, the sandboxed kernel), without the scan (autograder/integrity/scan.py), which
tests/test_integrity.py tests on its own.

- Every catalogued cheat that the comparison or the sandbox defeats scores 0 on the blank it tries
  to pass with a wrong or copied answer; none writes outside its submission folder, nor leaves
  anything in that folder (the kernel runs in a scratch copy of it).
- The grading kernel never holds the reference: it cannot import ``solutions`` or ``autograder``,
  read their files, or connect to an address outside; every lab's solved notebook still scores full
  marks there, and its blank release nothing.
- Edited and deleted test cells: the course's sanitize step (RestoreLabCells, then nbgrader's
  OverwriteCells) restores them, and the wrong blank still scores 0.

Cheats run on a trimmed notebook (set-up, answers, graded tests and student-added cells), two at a
time in separate processes, as ``grade --jobs 2`` runs them.
"""

from __future__ import annotations

import copy
import multiprocessing
import socket
import threading
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import nbformat
import pytest
from nbformat import NotebookNode
from nbgrader.utils import determine_grade

from autograder import cells
from autograder.catalogues import cheats, submissions
from autograder.labs import ROOT, Lab, get_lab
from defended_runs import graded_run, sanitized
from over_labs import LABS, about, chosen, over_labs

TRAIN = get_lab("train-kf")
DEFEATED = [c for c in cheats.catalogue(TRAIN) if c.caught_by & {cheats.GRADER, cheats.SANDBOX}]
OVERWRITE_CHEATS = [c for c in cheats.catalogue(TRAIN) if cheats.OVERWRITE in c.caught_by]
OTHER_LAB_CHEATS = ("patch-allclose", "open-exec-reference", "showtraceback", "gc-reference")
"""Cheats also run on the other labs (one each, in turn), to show the defences work beyond train-kf."""
OTHER_LAB_CASES = [(lab, OTHER_LAB_CHEATS[i % len(OTHER_LAB_CHEATS)]) for i, lab in enumerate(l for l in LABS if l != TRAIN)]

REACH = '''import socket, sys
found = {}
sys.path.insert(0, "ROOT")  # as a cheat would: the grading kernel's environment does not have it
try:
    import solutions
    found["import solutions"] = "worked"
except Exception as error:
    found["import solutions"] = type(error).__name__
try:
    __import__("solutions.train_kf.hidden_tests")
    found["import the hidden tests"] = "worked"
except Exception as error:
    found["import the hidden tests"] = type(error).__name__
for name, path in [("read solutions", "ROOT/solutions/train_kf/reference.py"), ("read autograder", "ROOT/autograder/__init__.py"),
                   ("read the gradebook", "COURSE/gradebook.db"), ("read the source", "ROOT/source/train-kf/train-kf.ipynb")]:
    try:
        open(path, "rb").read(1)
        found[name] = "worked"
    except Exception as error:
        found[name] = type(error).__name__
try:
    socket.create_connection(("127.0.0.1", PORT), timeout=2).close()
    found["connect out"] = "worked"
except Exception as error:
    found["connect out"] = type(error).__name__
found["loaded"] = sorted(m for m in sys.modules if m.split(".")[0] in ("solutions", "autograder"))
print(found)
'''
"""A cell appended to the solved notebook (ROOT, COURSE and PORT filled in): what the grading kernel can reach."""


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


def scores(nb: NotebookNode) -> dict[str, float]:
    """grade_id -> nbgrader's score of each graded test cell."""
    return {cells.grade_id(c): determine_grade(c)[0] for c in nb.cells if cells.is_autograded_test(c)}


def full_marks(lab: Lab) -> dict[str, float]:
    return {cells.grade_id(c): cells.meta(c)["points"] for c in cells.read(lab.source_notebook).cells
            if cells.is_autograded_test(c)}


@pytest.fixture(scope="module")
def listening():
    """A TCP server on the machine's loopback that the grading kernel must not reach."""
    server = socket.create_server(("127.0.0.1", 0))
    accepted = []

    def accept() -> None:
        try:
            accepted.append(server.accept())
        except OSError:  # shut down at teardown with no connection made: what the tests want
            pass

    thread = threading.Thread(target=accept, daemon=True)
    thread.start()
    yield server.getsockname()[1], accepted
    server.shutdown(socket.SHUT_RDWR)  # wakes the blocked accept(); a close alone leaves it on a stale descriptor
    thread.join(timeout=10)
    server.close()


@pytest.fixture(scope="module")
def course(tmp_path_factory) -> Path:
    """A course folder: its gradebook, and another student's folder the cheats try to reach."""
    course = tmp_path_factory.mktemp("course")
    other = course / "submitted" / "other-student" / TRAIN.module
    other.mkdir(parents=True)
    (other / "train-kf.ipynb").write_text("{}")
    return course


@pytest.fixture(scope="module")
def runs(course: Path, listening, pytestconfig) -> dict[str, NotebookNode | Exception]:
    """Every notebook these tests need (of the labs that ``pytest --lab`` chose), graded once by the
    execute step, two at a time."""
    jobs: dict[str, tuple[NotebookNode, Lab]] = {}
    train = chosen(pytestconfig, [TRAIN])
    for lab in chosen(pytestconfig, LABS):
        solved = sanitized(submissions.solved(lab), lab, course)
        if lab == TRAIN:
            solved.cells.append(nbformat.v4.new_code_cell(REACH.replace("ROOT", str(ROOT)).replace("COURSE", str(course)).replace("PORT", str(listening[0]))))
        jobs[f"solved/{lab.id}"] = solved, lab
        jobs[f"blank/{lab.id}"] = trimmed(sanitized(cells.read(lab.release_notebook), lab, course), lab), lab
    for cheat in DEFEATED if train else ():
        jobs[f"cheat/{cheat.name}/{TRAIN.id}"] = trimmed(sanitized(cheat.notebook(TRAIN), TRAIN, course), TRAIN), TRAIN
    for lab, name in OTHER_LAB_CASES:
        if chosen(pytestconfig, [lab]):
            jobs[f"cheat/{name}/{lab.id}"] = trimmed(sanitized(cheats.get(name).notebook(lab), lab, course), lab), lab
    for cheat in OVERWRITE_CHEATS if train else ():
        jobs[f"overwrite/{cheat.name}"] = trimmed(sanitized(cheat.notebook(TRAIN), TRAIN, course), TRAIN), TRAIN
    before = (course / "gradebook.db").read_bytes()
    with ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn")) as pool:
        futures = {name: pool.submit(graded_run, nbformat.writes(nb), lab.id, str(course)) for name, (nb, lab) in jobs.items()}
        results = {name: nbformat.reads(future.result(), as_version=4) for name, future in futures.items()}
    results["gradebook-bytes"] = (before, (course / "gradebook.db").read_bytes())  # type: ignore[assignment]
    return results


@over_labs
def test_the_solved_notebook_scores_full_marks_and_the_blank_nothing(runs, lab):
    assert scores(runs[f"solved/{lab.id}"]) == full_marks(lab)
    assert set(scores(runs[f"blank/{lab.id}"]).values()) == {0}


@about(TRAIN)
def test_the_grading_kernel_cannot_reach_the_reference_the_course_or_the_network(runs, listening):
    """Each of these would work in an unsandboxed kernel (tests/test_sandbox.py shows it with the
    sandbox off): the import, the reads, the connection to a server on the loopback."""
    reach = runs[f"solved/{TRAIN.id}"].cells[-1]
    [output] = [o for o in reach.outputs if o.output_type == "stream"]
    found = eval(output.text)  # a dict the cell printed
    assert found.pop("loaded") == [], "the grading kernel loaded the reference or the grader's code"
    assert "worked" not in found.values(), found
    assert found["import solutions"] == "ModuleNotFoundError"
    assert {found[k] for k in ("read solutions", "read autograder", "read the gradebook", "read the source")} == {"PermissionError"}
    assert found["connect out"] in ("OSError", "ConnectionRefusedError", "TimeoutError"), found
    assert listening[1] == [], "the kernel connected to the test's server"


@about(TRAIN)
@pytest.mark.parametrize("cheat", DEFEATED, ids=[c.name for c in DEFEATED])
def test_a_cheat_gains_nothing_without_the_scan(runs, cheat):
    """The blank it tries to pass with a wrong answer, or with the reference's, scores 0."""
    got = scores(runs[f"cheat/{cheat.name}/{TRAIN.id}"])
    if cheat.plants_mistake or cheat.games == "blank":
        assert got[f"test_{cheat.aim or cheats.target(TRAIN)}"] == 0, got


@pytest.mark.parametrize("lab, name", OTHER_LAB_CASES, ids=[f"{lab.id}-{name}" for lab, name in OTHER_LAB_CASES])
def test_cheats_gain_nothing_in_every_lab(runs, lab, name):
    assert scores(runs[f"cheat/{name}/{lab.id}"])[f"test_{cheats.target(lab)}"] == 0


@about(*LABS)
def test_nothing_was_written_outside_the_submission(runs, course):
    before, after = runs["gradebook-bytes"]
    assert before == after
    assert not (course / "submitted" / "other-student" / TRAIN.module / "notes.txt").exists()
    assert (course / "submitted" / "other-student" / TRAIN.module / "train-kf.ipynb").read_text() == "{}"
    assert list((course / "submitted" / "student" / TRAIN.id).glob("*.ipynb")) == []
    # the kernel ran in a scratch copy: nothing it left (a symbolic link in the notebook's place) is
    # in the folder where nbgrader writes the graded notebook
    assert [p for p in (course / "submitted" / "student").rglob("*") if p.is_symlink()] == []


@about(TRAIN)
@pytest.mark.parametrize("cheat", OVERWRITE_CHEATS, ids=[c.name for c in OVERWRITE_CHEATS])
def test_nbgrader_restores_test_cells_and_the_wrong_blank_scores_zero(runs, cheat):
    # nbgrader 0.9.6 alone fails on a test cell retagged with an unknown grade_id (KeyError
    # 'grade_id'); RestoreLabCells drops such metadata first, so every one of these is graded.
    nb = runs[f"overwrite/{cheat.name}"]
    blank = cheats.target(TRAIN)
    source = {cells.grade_id(c): c.source for c in cells.read(TRAIN.source_notebook).cells if cells.is_autograded_test(c)}
    restored = [c for c in nb.cells if cells.is_autograded_test(c) and cells.grade_id(c) == f"test_{blank}"]
    assert len(restored) == 1 and restored[0].source.endswith(source[f"test_{blank}"])
    ids = [c.id for c in nb.cells]
    assert len(ids) == len(set(ids)), "a restored cell shares its cell id with the student's copy"
    nbformat.validate(nb)
    got = scores(nb)
    assert set(got) == set(source)
    assert got[f"test_{blank}"] == 0
    assert all(score > 0 for cell, score in got.items() if cell != f"test_{blank}"), got

"""One class graded in shards (`grade --shard K/N`, README: Large classes), each shard a process of
its own as a batch system starts it, into one PostgreSQL gradebook on a real server on loopback
(tests/postgres_server.py), then put together by `python -m autograder export`.

The class: 12 submissions of two labs (train-kf and nonlinear-filters, the quickest to grade), per
lab the demo's blank, solved, two catalogued mistakes, a cheat and a fault: every kind of outcome,
and shards of 6, 4, 1 and 1 submissions when four grade it (so the largest can be killed part-way).
The class is graded five times over (the baseline, two shards, four, the rerun and the overlaps),
so each submission more costs CI about half a minute.
benchmarks/shards.py times the same class at 20 a lab. The baseline is the class graded by
one `grade --jobs 1` into a fresh gradebook; its rows are checked against the catalogues. Then:
- two shards at once, each in a course folder of its own (machines with no shared folder): the
  export fails, naming every submission whose files are not in its folder, until each shard's
  autograded/ and feedback/ are copied there; then its grades.csv is the baseline's, row for row, and
  `report` from that PostgreSQL gradebook counts what the class was built with, as the baseline's
  report (written by its `grade`) does;
- four shards at once in one shared course folder, one of them killed (SIGKILL, with its kernels)
  part-way: the export names what the killed shard had not finished; rerun alone, the shard
  completes the class, and grades.csv is the baseline's;
- overlapping shards (1/2 twice, 2/2 and 1/1 at once) are idempotent: each submission is graded
  by one process at a time, and grades.csv is the baseline's;
- four processes that set up an empty gradebook at once (what nbgrader alone fails at) all succeed.
"""

from __future__ import annotations

import hashlib
import multiprocessing
import re
import shutil
import subprocess
import sys
import time

import pytest
from nbgrader.api import Gradebook

from postgres_server import postgres_url  # noqa: F401 (a fixture: this module's own server)
import shard_runs
from autograder import cells
from autograder.catalogues import faults, synthetic_class
from autograder.__main__ import build_parser, main
from autograder.catalogues import demo
from autograder.labs import ROOT, get_lab
from autograder.pipeline import class_report, grades, grading, intake
from autograder.pipeline.nbgrader_apps import feedback_page
from autograder.pipeline.shards import NotShared, Shard, shard_of

LABS = [get_lab("train-kf"), get_lab("nonlinear-filters")]
PER_LAB = 6


@pytest.fixture(scope="module")
def klass(tmp_path_factory):
    """(the class folder, (student, lab) -> what grading must make of the submission)."""
    folder = tmp_path_factory.mktemp("shards") / "class"
    return folder, demo.write_demo_class(LABS, folder, size=PER_LAB)


def listed(exported) -> set[tuple[str, str]]:
    """The (student, lab) submissions that a failed export names, one per line: "  student lab: no ..."."""
    return {tuple(line.split(":")[0].split()) for line in exported.stderr.splitlines() if line.startswith("  ")}


def students_of(klass, shard: Shard) -> set[tuple[str, str]]:
    """The (student, lab) submissions of the class that ``shard`` grades."""
    return {key for key in klass[1] if shard.takes(key[0])}


@pytest.fixture(scope="module")
def baseline_and_two_shards(postgres_url, klass, tmp_path_factory):
    """The class graded by one `grade --jobs 1` into a fresh gradebook (the baseline), and, at the
    same time, by shards 1/2 and 2/2 into another, each in a course folder of its own. Returns
    (baseline course folder, its URL, the shards' folders, their URL)."""
    base = tmp_path_factory.mktemp("two-shards")
    baseline, shard_dirs = base / "baseline", [base / "shard-1", base / "shard-2"]
    baseline_url, shards_url = shard_runs.new_database(postgres_url, "baseline"), shard_runs.new_database(postgres_url, "two")
    runs = [shard_runs.start_grade(klass[0], baseline, baseline_url, base / "baseline.log", "--jobs", "1")]
    runs += [shard_runs.start_grade(klass[0], folder, shards_url, base / f"shard-{k}.log", "--shard", f"{k}/2", "--jobs", "1")
             for k, folder in enumerate(shard_dirs, 1)]
    for run in runs:
        run.finish()
    return baseline, baseline_url, shard_dirs, shards_url


@pytest.fixture(scope="module")
def baseline_csv(baseline_and_two_shards):
    """The baseline's grades.csv, written by `export` as for the shards."""
    baseline, baseline_url, _, _ = baseline_and_two_shards
    exported = shard_runs.export(baseline, baseline_url)
    assert exported.returncode == 0, exported.stderr
    return shard_runs.csv_rows(baseline / "grades.csv")


def test_the_baseline_grades_the_class_as_catalogued(baseline_and_two_shards, baseline_csv, klass, monkeypatch):
    baseline, baseline_url, _, _ = baseline_and_two_shards
    monkeypatch.setenv("GRADEBOOK_URL", baseline_url)
    rows = grades.read_grades(baseline, LABS)
    kinds = {outcome.kind for outcome in klass[1].values()}
    assert len(rows) == len(klass[1]) == 2 * PER_LAB and kinds >= {"mistake", "cheat", "fault", "solved", "blank"}
    assert demo.unexpected(rows, klass[1]) == []
    assert len(baseline_csv) == 1 + len(rows)


def test_two_shards_without_a_shared_folder_give_the_baseline_once_gathered(baseline_and_two_shards, baseline_csv,
                                                                             klass, tmp_path):
    _, _, shard_dirs, url = baseline_and_two_shards
    gathered = tmp_path / "course"
    gathered.mkdir()
    nothing = shard_runs.export(gathered, url)
    assert nothing.returncode == 1
    assert listed(nothing) == set(klass[1])
    plain = subprocess.run([sys.executable, "-m", "nbgrader", "export", f"--CourseDirectory.root={gathered}"], cwd=ROOT,
                           env=shard_runs.environment(url), capture_output=True, text=True, timeout=300)
    assert plain.returncode == 1 and f"lacks {len(klass[1])} submissions of the gradebook" in plain.stderr

    for folder in ("autograded", "feedback"):  # the copy step: shard 1's files only, so far
        shutil.copytree(shard_dirs[0] / folder, gathered / folder, dirs_exist_ok=True)
    half = shard_runs.export(gathered, url)
    assert half.returncode == 1 and "no autograded/" in half.stderr and "and no feedback/" in half.stderr
    assert listed(half) == students_of(klass, Shard(2, 2)) != set()

    for folder in ("autograded", "feedback"):
        shutil.copytree(shard_dirs[1] / folder, gathered / folder, dirs_exist_ok=True)
    whole = shard_runs.export(gathered, url)
    assert whole.returncode == 0, whole.stderr
    assert shard_runs.csv_rows(gathered / "grades.csv") == baseline_csv

    reported = shard_runs.report(gathered, url)
    assert reported.returncode == 0, reported.stderr
    baseline = baseline_and_two_shards[0]
    for lab in LABS:
        outcomes = {student: o for (student, lab_id), o in klass[1].items() if lab_id == lab.id}
        counts = shard_runs.csv_rows(gathered / "report" / f"{lab.id}.csv")
        assert report_counts(counts) == built_counts(lab, outcomes)
        assert sum(int(n) for _, _, what, _, n in counts[1:] if what == class_report.SCORE) == len(outcomes)
        for name in (f"{lab.id}.csv", f"{lab.id}-students.csv"):
            assert shard_runs.csv_rows(gathered / "report" / name) == shard_runs.csv_rows(baseline / "report" / name)
        page, baseline_page = (without_figure(folder / "report" / f"{lab.id}.html") for folder in (gathered, baseline))
        assert page == baseline_page and f"<p>{len(outcomes)} graded submissions." in page


def report_counts(rows: list[list[str]]) -> dict[tuple[str, str, str], int]:
    """(cell, what, detail) -> count, from a report's CSV (header first): the counts that are not 0,
    without the score bins and the failing visible checks (compared with the baseline's), and with
    the error's name of a blank lost another way, outside a flagged submission, as "an error"."""
    found: dict[tuple[str, str, str], int] = {}
    for _, cell, what, detail, n in rows[1:]:
        if int(n) and what not in (class_report.SCORE, class_report.VISIBLE_FAILED):
            key = (cell, what, "an error" if what == class_report.OTHER and detail != class_report.FLAGGED_DETAIL else detail)
            found[key] = found.get(key, 0) + int(n)
    return found


def without_figure(page) -> str:
    return re.sub(r'"data:image/png;base64,[A-Za-z0-9+/=]*"', "", page.read_text())


def built_counts(lab, outcomes: dict[str, synthetic_class.Outcome]) -> dict[tuple[str, str, str], int]:
    """What the class report of ``lab`` must count (its counts that are not 0, score bins left out),
    from each submission's Outcome as the class was built: the blank leaves every blank unwritten, a
    mistake loses its own blank to that mistake, a flagged cheat the blanks it games, a fault its blank
    (by an error), and every other blank has full marks. A fault is counted as faulted when the grader
    notes it: every one but a NumPy warning, which only fails its blank's test (README: Careless submissions)."""
    source = cells.read(lab.source_notebook).cells
    tests = [cells.grade_id(c) for c in source if cells.is_autograded_test(c)]
    written = [cells.grade_id(c) for c in source if cells.meta(c).get("grade") and c.cell_type == "markdown"]
    found: dict[tuple[str, str, str], int] = {("", class_report.SUBMITTED, ""): len(outcomes)}

    def add(key: tuple[str, str, str]) -> None:
        found[key] = found.get(key, 0) + 1

    for outcome in outcomes.values():
        zero = tests if outcome.zero is None else outcome.zero
        for cell in tests:
            if outcome.kind == "blank":
                add((cell, class_report.NOT_WRITTEN, ""))
            elif cell not in zero:
                add((cell, class_report.FULL, ""))
            elif outcome.kind == synthetic_class.MISTAKE:
                add((cell, class_report.MISTAKE, outcome.mistake))
            elif outcome.flagged:
                add((cell, class_report.OTHER, class_report.FLAGGED_DETAIL))
            else:
                add((cell, class_report.OTHER, "an error"))
        if outcome.kind != "blank":  # nbgrader scores a written answer left as released 0 itself
            for cell in written:
                add((cell, class_report.WAITING, ""))
        if outcome.flagged:
            add(("", class_report.FLAGGED, ""))
        if outcome.kind == synthetic_class.FAULT and outcome.student != faults.get("numpy-warning").student_id(lab):
            add(("", class_report.FAULTED, ""))
    return found


def test_four_shards_in_a_shared_folder_one_killed_and_rerun_give_the_baseline(postgres_url, klass, baseline_csv, tmp_path):
    url, course = shard_runs.new_database(postgres_url, "four"), tmp_path / "course"
    victim = max((Shard(k, 4) for k in range(1, 5)), key=lambda s: len(students_of(klass, s)))
    runs = {shard: shard_runs.start_grade(klass[0], course, url, tmp_path / f"shard-{shard.index}.log",
                                          "--shard", str(shard), "--jobs", "1") for shard in (Shard(k, 4) for k in range(1, 5))}
    theirs = students_of(klass, victim)

    def finished() -> set[tuple[str, str]]:
        return {(s, lab) for s, lab in theirs if feedback_page(course, lab, s).exists()}

    deadline = time.monotonic() + 600
    while not finished() and runs[victim].process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.2)
    runs[victim].kill()
    done = finished()
    assert 0 < len(done) < len(theirs), f"the shard was not killed part-way: {len(done)} of {len(theirs)} graded"
    for shard, run in runs.items():
        if shard != victim:
            run.finish()

    cut_short = shard_runs.export(course, url)
    assert cut_short.returncode == 1
    assert listed(cut_short) == theirs - done

    shard_runs.start_grade(klass[0], course, url, tmp_path / "rerun.log", "--shard", str(victim)).finish()
    rerun = shard_runs.export(course, url)
    assert rerun.returncode == 0, rerun.stderr
    assert shard_runs.csv_rows(course / "grades.csv") == baseline_csv


def test_overlapping_shards_are_idempotent(postgres_url, klass, baseline_csv, tmp_path):
    """1/2 twice, 2/2 and 1/1 at once, on two students of the class (one in each half), both labs each."""
    both = [s for s in sorted({s for s, _ in klass[1]}) if all((s, lab.id) in klass[1] for lab in LABS)]
    chosen = [next(s for s in both if shard_of(s, 2) == k) for k in (1, 2)]
    small = tmp_path / "class"
    for student in chosen:
        shutil.copytree(klass[0] / student, small / student)
    url, course = shard_runs.new_database(postgres_url, "overlap"), tmp_path / "course"
    runs = [shard_runs.start_grade(small, course, url, tmp_path / f"run-{n}.log", "--shard", spec, "--jobs", "1")
            for n, spec in enumerate(("1/2", "1/2", "2/2", "1/1"))]
    for run in runs:
        run.finish()
    exported = shard_runs.export(course, url)
    assert exported.returncode == 0, exported.stderr
    assert shard_runs.csv_rows(course / "grades.csv") == [baseline_csv[0]] + [r for r in baseline_csv[1:] if r[0] in chosen]


def _set_up(workdir, by_lab, barrier) -> None:
    barrier.wait()
    grading.set_up(LABS, workdir, by_lab)


def test_processes_setting_up_one_gradebook_at_once_all_succeed(postgres_url, klass, tmp_path, monkeypatch):
    """nbgrader alone fails here: its tables, the course, the labs and students created twice, and
    generate_assignment's cells deleted by one process while another writes them."""
    url = shard_runs.new_database(postgres_url, "set-up")
    monkeypatch.setenv("GRADEBOOK_URL", url)  # the spawned processes inherit it
    by_lab = intake.class_list(klass[0], LABS)
    context = multiprocessing.get_context("spawn")
    with context.Manager() as manager, context.Pool(4) as pool:
        barrier = manager.Barrier(4)
        pending = [pool.apply_async(_set_up, (tmp_path / f"course-{k}", by_lab, barrier)) for k in range(4)]
        for result in pending:
            result.get(timeout=300)
    with Gradebook(url) as gb:
        for lab in LABS:
            assert sorted(s.student_id for s in gb.find_assignment(lab.id).submissions) == by_lab[lab.id]
            source = cells.read(lab.source_notebook)
            graded = {cells.grade_id(c) for c in source.cells if cells.meta(c).get("grade")}
            assert {c.name for c in gb.find_notebook(lab.id, lab.id).grade_cells} == graded


def test_the_split_is_by_the_student_ids_sha256_and_balanced():
    students = [f"s{k:05d}" for k in range(4000)]
    for count in (2, 4, 7):
        assert [shard_of(s, count) for s in students[:50]] == [
            int(hashlib.sha256(s.encode()).hexdigest()[:16], 16) % count + 1 for s in students[:50]]
        sizes = [sum(shard_of(s, count) == k for s in students) for k in range(1, count + 1)]
        expected, sigma = len(students) / count, (len(students) * (1 / count) * (1 - 1 / count)) ** 0.5
        assert all(abs(size - expected) < 4 * sigma for size in sizes), sizes  # false fail < 1e-4 per shard
    assert all(sum(Shard(k, 4).takes(s) for k in range(1, 5)) == 1 for s in students)


def test_a_shard_takes_the_same_students_whichever_files_are_present(klass, tmp_path):
    shard = Shard(1, 2)
    whole = intake.import_submissions(klass[0], tmp_path / "whole", LABS, shard.takes)
    partial_class = tmp_path / "partial"
    for student in sorted({s for s, _ in klass[1]})[::2]:
        shutil.copytree(klass[0] / student, partial_class / student)
    partial = intake.import_submissions(partial_class, tmp_path / "partial-course", LABS, shard.takes)
    for lab in LABS:
        present = intake.class_list(partial_class, [lab])[lab.id]
        assert partial[lab.id] == [s for s in whole[lab.id] if s in present]
        assert 0 < len(whole[lab.id]) < PER_LAB


def test_shard_arguments_are_checked(capsys):
    for wrong in ("0/2", "3/2", "2", "a/b", "1/0"):
        with pytest.raises(SystemExit):
            build_parser().parse_args(["grade", "class", "--shard", wrong])
        assert "is not a shard: give K/N" in capsys.readouterr().err
    assert build_parser().parse_args(["grade", "class", "--shard", "2/4"]).shard == Shard(2, 4)


def test_a_shard_refuses_an_sqlite_gradebook(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv("GRADEBOOK_URL", raising=False)
    with pytest.raises(NotShared, match="set GRADEBOOK_URL to a PostgreSQL database"):
        grading.grade(tmp_path / "class", tmp_path / "course", shard=Shard(1, 2))
    assert not (tmp_path / "course").exists()
    assert main(["grade", str(tmp_path / "class"), "--workdir", str(tmp_path / "course"), "--shard", "1/2"]) == 1
    assert "--shard needs a gradebook that every shard reaches" in capsys.readouterr().err

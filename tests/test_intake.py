"""Intake of an LMS download through nbgrader's zip_collect: files named by student, mapped to our
student ids, into the layout `python -m autograder grade` takes. Nothing is dropped silently."""

import os
import re
import secrets
import subprocess
import sys
import tracemalloc
import zipfile
from datetime import datetime, timezone
from pathlib import Path

import nbformat
import pytest
from nbgrader.utils import parse_utc

from autograder.pipeline import grading, intake
from autograder.catalogues import submissions
from autograder.__main__ import main
from autograder.pipeline.collect import TIMED_PATTERN, IntakeError, collect
from autograder.labs import ROOT, get_lab

LAB = get_lab("train-kf")
STUDENTS = "lms_name,student_id\nalice,s001\nbob,s002\ncarol,s003\ndave,s004\n"


def notebook(tag: str) -> str:
    """The solved notebook, marked so that a test can tell which file was collected."""
    nb = submissions.solved(LAB)
    nb.metadata["intake_test"] = tag
    return nbformat.writes(nb)


def tag(path) -> str:
    return nbformat.read(path, as_version=4).metadata["intake_test"]


@pytest.fixture
def download(tmp_path):
    """An LMS zip with a folder inside: two files of alice (the newer one wins), bob without a
    time, carol's file under another name, a stranger, a receipt, and a name the pattern misses."""
    files = {
        "alice_2026-10-02-23-30-00_train-kf.ipynb": notebook("alice-old"),
        "alice_2026-10-03-01-00-00_train-kf.ipynb": notebook("alice-new"),
        "bob_train-kf.ipynb": notebook("bob"),
        "carol_my work.ipynb": notebook("carol"),
        "mallory_train-kf.ipynb": notebook("mallory"),
        "receipt.txt": "submitted",
        "untitled.ipynb": notebook("untitled"),
    }
    path = tmp_path / "lms.zip"
    with zipfile.ZipFile(path, "w") as archive:
        for name, text in files.items():
            archive.writestr(f"export/{name}", text)
    students = tmp_path / "students.csv"
    students.write_text(STUDENTS)
    return path, students


def test_collects_a_zip_into_the_grading_layout_and_reports_every_other_file(download, tmp_path):
    zip_path, students = download
    out = tmp_path / "SUBMISSIONS"
    report = collect(LAB, zip_path, students, out, zone="Europe/London", times_in_names=True)

    assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file()) == [
        "s001/train-kf/timestamp.txt", "s001/train-kf/train-kf.ipynb",
        "s002/train-kf/train-kf.ipynb", "s003/train-kf/train-kf.ipynb",
    ]
    assert report.students == ["s001", "s002", "s003"]
    assert tag(out / "s001/train-kf/train-kf.ipynb") == "alice-new"
    assert tag(out / "s003/train-kf/train-kf.ipynb") == "carol"
    # 01:00 in London in October (BST, UTC+1) is midnight UTC, as nbgrader stores it
    assert (out / "s001/train-kf/timestamp.txt").read_text() == "2026-10-03 00:00:00"

    assert sorted(report.skipped) == [
        ("lms/export/mallory_train-kf.ipynb", "unknown student 'mallory': not in the student list"),
        ("lms/export/receipt.txt", "not a notebook"),
        ("lms/export/untitled.ipynb", "the file name does not match the LMS pattern"),
    ]
    assert report.superseded == [("lms/export/alice_2026-10-02-23-30-00_train-kf.ipynb", "s001")]
    assert report.renamed == [("lms/export/carol_my work.ipynb", "s003")]
    assert report.missing == ["s004"]

    # grade() takes this layout as it is, timestamp included
    workdir = tmp_path / "course"
    assert intake.import_submissions(out, workdir, [LAB]) == {"train-kf": ["s001", "s002", "s003"]}
    assert (workdir / "submitted/s001/train-kf/timestamp.txt").read_text() == "2026-10-03 00:00:00"


def test_collects_a_folder_with_the_lms_pattern_given(tmp_path):
    """A Moodle-style download: one folder per student, named by the student's full name."""
    download = tmp_path / "moodle"
    for folder in ("Alice Smith_101_assignsubmission_file_", "Bob Jones_102_assignsubmission_file_"):
        (download / folder).mkdir(parents=True)
        (download / folder / "train-kf.ipynb").write_text(notebook(folder))
    students = tmp_path / "students.csv"
    students.write_text("lms_name,student_id\nAlice Smith,s001\nBob Jones,s002\n")
    pattern = r"(?:^|/)(?P<student_id>[^/_]+)_\d+_assignsubmission_file_/[^/]+\.ipynb$"
    report = collect(LAB, download, students, tmp_path / "out", pattern=pattern)
    assert report.students == ["s001", "s002"] and not report.skipped and not report.renamed
    assert tag(tmp_path / "out/s002/train-kf/train-kf.ipynb") == "Bob Jones_102_assignsubmission_file_"
    assert not (tmp_path / "out/s002/train-kf/timestamp.txt").exists()


def test_command_reports_unknown_names_and_exits_nonzero(download, tmp_path, capsys):
    zip_path, students = download
    out = tmp_path / "SUBMISSIONS"
    assert main(["collect", "train-kf", str(zip_path), "--students", str(students), "--out", str(out),
                 "--times-in-names"]) == 1
    printed = capsys.readouterr().out
    assert "NOT COLLECTED lms/export/mallory_train-kf.ipynb: unknown student 'mallory'" in printed
    assert "no submission from: s004" in printed
    # times in file names are UTC unless --timezone says otherwise
    assert (out / "s001/train-kf/timestamp.txt").read_text() == "2026-10-03 01:00:00"


def test_two_files_of_one_student_without_times_are_that_students_refusal(tmp_path):
    """Neither is collected, with the reason, and the rest of the class is (nbgrader would stop the
    whole collect: "Duplicate submission file")."""
    download = tmp_path / "lms"
    download.mkdir()
    for name in ("bob_train-kf.ipynb", "bob_train-kf (1).ipynb", "alice_train-kf.ipynb"):
        (download / name).write_text(notebook(name))
    students = tmp_path / "students.csv"
    students.write_text(STUDENTS)
    report = collect(LAB, download, students, tmp_path / "out")
    assert report.students == ["s001"] and tag(tmp_path / "out/s001/train-kf/train-kf.ipynb") == "alice_train-kf.ipynb"
    reason = ("s002 has 2 notebooks here (bob_train-kf (1).ipynb, bob_train-kf.ipynb) and no submission time in "
              "each name to choose the newest: none is collected (keep one)")
    assert sorted(report.skipped) == [("bob_train-kf (1).ipynb", reason), ("bob_train-kf.ipynb", reason)]
    assert "s002" in report.missing


def poc_download(tmp_path, members: dict[str, str], upload="bob_2026-10-09-10-00-00_upload.zip"):
    """The review's folder download: alice's and carol's notebooks, and bob's zip of ``members``."""
    download = tmp_path / "lms"
    download.mkdir()
    (download / "alice_2026-10-01-10-00-00_train-kf.ipynb").write_text(notebook("alice"))
    (download / "carol_train-kf.ipynb").write_text(notebook("carol"))
    with zipfile.ZipFile(download / upload, "w") as archive:
        for name, text in members.items():
            archive.writestr(name, text)
    students = tmp_path / "students.csv"
    students.write_text(STUDENTS)
    return download, students


def test_a_file_in_a_students_upload_cannot_claim_another_student_or_time(tmp_path):
    """The student and the time come from the name the LMS wrote (bob's zip), never from a name
    inside the upload: bob's member named for alice, dated 2099, and his own member dated 2000 are
    refused, for bob, with the reason; alice keeps her notebook and her time."""
    download, students = poc_download(tmp_path, {"alice_2099-01-01-00-00-00_x.ipynb": "FORGED BY BOB",
                                                 "bob_2000-01-01-00-00-00_train-kf.ipynb": notebook("bob-backdated")})
    out = tmp_path / "out"
    report = collect(LAB, download, students, out, times_in_names=True)
    assert report.students == ["s001", "s003"]
    assert tag(out / "s001/train-kf/train-kf.ipynb") == "alice"
    assert (out / "s001/train-kf/timestamp.txt").read_text() == "2026-10-01 10:00:00"
    assert not (out / "s002").exists()
    upload = "bob_2026-10-09-10-00-00_upload"
    assert sorted(report.skipped) == [
        (f"{upload}/alice_2099-01-01-00-00-00_x.ipynb",
         f"it is in bob (s002)'s upload {upload}.zip, but its name says it is 'alice''s: a file in an upload is "
         "the uploader's, so it is not collected"),
        (f"{upload}/bob_2000-01-01-00-00-00_train-kf.ipynb",
         f"it is in bob (s002)'s upload {upload}.zip, but its name gives its own submission time: the time is "
         "the upload's, so it is not collected"),
    ]


def test_a_students_upload_without_times_cannot_stop_the_class(tmp_path):
    """bob_upload.zip holding alice_x.ipynb made nbgrader refuse a duplicate of alice's and stop the
    whole collect; now it is bob's refusal, and bob's own notebook beside it is his, at his zip's time."""
    download, students = poc_download(tmp_path, {"alice_x.ipynb": "FORGED BY BOB", "train-kf.ipynb": notebook("bob")})
    out = tmp_path / "out"
    report = collect(LAB, download, students, out, times_in_names=True)
    assert report.students == ["s001", "s002", "s003"]
    assert tag(out / "s001/train-kf/train-kf.ipynb") == "alice" and tag(out / "s002/train-kf/train-kf.ipynb") == "bob"
    assert (out / "s002/train-kf/timestamp.txt").read_text() == "2026-10-09 10:00:00"
    assert [path for path, _ in report.skipped] == ["bob_2026-10-09-10-00-00_upload/alice_x.ipynb"]


def test_a_file_name_that_reads_as_an_impossible_time_is_that_students_refusal(tmp_path):
    """Adversarial review: an LMS that writes <name>_<student's file name> let dave name his file
    2026-13-45-99-99-99_sub.ipynb, which the default pattern read as a time: collect raised and
    collected nobody."""
    download = tmp_path / "download"
    download.mkdir()
    (download / "bob_2026-10-09-11-00-00_sub.ipynb").write_text(notebook("bob"))
    (download / "dave_2026-13-45-99-99-99_sub.ipynb").write_text(notebook("dave"))
    students = tmp_path / "students.csv"
    students.write_text(STUDENTS)
    report = collect(LAB, download, students, tmp_path / "out", times_in_names=True)
    assert report.students == ["s002"] and tag(tmp_path / "out/s002/train-kf/train-kf.ipynb") == "bob"
    [(path, reason)] = report.skipped
    assert path == "dave_2026-13-45-99-99-99_sub.ipynb" and "dave (s004)" in reason and "not a date" in reason


def test_by_default_no_time_is_read_from_a_name_the_student_chose(tmp_path):
    """A fourth review: with an LMS that writes <name>_<the student's file name>, a student who named a
    late file 2026-01-01-00-00-00_x.ipynb was collected with that time, so with no late penalty. By
    default no time is read from a name; --times-in-names reads it, for an LMS that writes its own.
    Fails on the code before (the default read it)."""
    download = tmp_path / "download"
    download.mkdir()
    (download / "bob_2026-01-01-00-00-00_x.ipynb").write_text(notebook("bob"))
    students = tmp_path / "students.csv"
    students.write_text(STUDENTS)
    report = collect(LAB, download, students, tmp_path / "out")
    assert report.students == ["s002"] and not (tmp_path / "out/s002/train-kf/timestamp.txt").exists()
    collect(LAB, download, students, tmp_path / "timed", times_in_names=True)
    assert (tmp_path / "timed/s002/train-kf/timestamp.txt").read_text() == "2026-01-01 00:00:00"


def hub_class(course, students: dict) -> None:
    """``course/submitted/<student>/<lab>/`` as nbgrader's ``collect`` leaves it, each student's ``timestamp.txt``
    and ``submission_secret.txt`` made by ``students[student]`` (folder -> None), which may plant anything."""
    for student, plant in students.items():
        folder = course / "submitted" / student / LAB.id
        folder.mkdir(parents=True)
        (folder / LAB.notebook_name).write_text(notebook(student))
        (folder / "timestamp.txt").write_text("2026-10-09 10:00:00.000000 UTC")
        (folder / intake.SECRET).write_text(secrets.token_hex(64))
        plant(folder)


def notes_of(path) -> str:
    """The text of the grader's notes of the notebook at ``path``."""
    from autograder.pipeline.restore import grader_notes
    return " ".join(note.text for note in grader_notes(nbformat.read(path, as_version=4)))


def test_a_timestamp_that_is_no_time_is_replaced_by_the_due_date_with_a_note(tmp_path, monkeypatch):
    """Adversarial review: a timestamp.txt that nbgrader cannot read made the submission "not graded"; then, left
    out, release_feedback stopped at that student (FileNotFoundError) and released no one's feedback after them.
    The lab's due date stands in (not late), or with no due date the time of intake; on a hub, a missing one too."""
    def stamp(text):
        return lambda folder: (folder / "timestamp.txt").write_text(text)
    hub_class(tmp_path / "course", {"s001": stamp("the day before yesterday"), "s002": stamp(""),
                                    "s003": lambda folder: (folder / "timestamp.txt").unlink(), "s004": lambda _: None})
    intake.import_submissions(tmp_path / "course" / "submitted", tmp_path / "course", [LAB])
    taken = tmp_path / "course" / intake.EXCHANGE_INTAKE
    for student in ("s001", "s002", "s003"):
        assert (taken / student / LAB.id / "timestamp.txt").read_text() == "2026-10-09 22:59:00.000000 UTC"
        assert ("timestamp.txt is missing or does not hold a time, so the lab's due date, 2026-10-09 22:59:00.000000 "
                "UTC, stands in for it: no late penalty was computed. Check when it was submitted."
                ) in notes_of(taken / student / LAB.id / LAB.notebook_name)
    assert (taken / "s004" / LAB.id / "timestamp.txt").read_text() == "2026-10-09 10:00:00.000000 UTC"
    assert notes_of(taken / "s004" / LAB.id / LAB.notebook_name) == ""

    monkeypatch.setattr(intake, "read_due_dates", lambda path: {})
    before = datetime.now(timezone.utc).replace(microsecond=0)
    intake.import_submissions(tmp_path / "course" / "submitted", tmp_path / "course", [LAB])
    written = parse_utc((taken / "s001" / LAB.id / "timestamp.txt").read_text()).replace(tzinfo=timezone.utc)
    assert before <= written <= datetime.now(timezone.utc)
    assert "the time it was taken in" in notes_of(taken / "s001" / LAB.id / LAB.notebook_name)
    # SUBMISSIONS elsewhere (an LMS download): no timestamp.txt is no submission time, never late, no note
    (tmp_path / "subs/s005" / LAB.id).mkdir(parents=True)
    (tmp_path / "subs/s005" / LAB.id / LAB.notebook_name).write_text(notebook("s005"))
    intake.import_submissions(tmp_path / "subs", tmp_path / "course", [LAB])
    assert sorted(p.name for p in (tmp_path / "course/submitted/s005" / LAB.id).iterdir()) == [LAB.notebook_name]


def test_a_timestamp_that_is_a_directory_or_a_link_is_unreadable_and_grading_goes_on(tmp_path):
    """Adversarial review: a timestamp.txt that is a directory stopped `grade` for the whole class
    (IsADirectoryError); only a regular file is read, not a link or a FIFO either."""
    def replace(make):
        def plant(folder):
            (folder / "timestamp.txt").unlink()
            make(folder / "timestamp.txt")
        return plant
    other = tmp_path / "elsewhere.txt"
    other.write_text("2026-10-01 10:00:00.000000 UTC")
    hub_class(tmp_path / "course", {"s001": replace(Path.mkdir), "s002": replace(lambda p: p.symlink_to(other)),
                                    "s003": replace(os.mkfifo)})
    assert intake.import_submissions(tmp_path / "course" / "submitted", tmp_path / "course", [LAB]) == {
        LAB.id: ["s001", "s002", "s003"]}
    for student in ("s001", "s002", "s003"):
        folder = tmp_path / "course" / intake.EXCHANGE_INTAKE / student / LAB.id
        assert (folder / "timestamp.txt").read_text() == "2026-10-09 22:59:00.000000 UTC"
        assert "stands in for it" in notes_of(folder / LAB.notebook_name)


def test_a_huge_timestamp_is_read_no_further_than_its_first_bytes(tmp_path):
    """Adversarial review: timestamp.txt was read whole before its cut (a 2 GB sparse file took 2.1 GB)."""
    def huge(folder):
        with open(folder / "timestamp.txt", "r+b") as handle:
            handle.truncate(200_000_000)
    hub_class(tmp_path / "course", {"s001": huge})
    tracemalloc.start()
    try:
        intake.import_submissions(tmp_path / "course" / "submitted", tmp_path / "course", [LAB])
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 50_000_000
    folder = tmp_path / "course" / intake.EXCHANGE_INTAKE / "s001" / LAB.id
    assert (folder / "timestamp.txt").read_bytes() == b"2026-10-09 10:00:00.000000 UTC".ljust(200, b"\0")


def test_a_secret_not_of_nbgraders_form_is_replaced_by_a_fresh_one_with_a_note(tmp_path):
    """Adversarial review: an empty, non-UTF-8 or directory submission_secret.txt was copied unchecked (or dropped),
    and release_feedback then stopped for the class (AssertionError, UnicodeDecodeError, FileNotFoundError). Only a
    regular file of nbgrader's form (secrets.token_hex(64)) is copied; anything else, or on a hub none, gets a fresh
    one, and the note says that the student cannot fetch that page."""
    def secret(make):
        def plant(folder):
            (folder / intake.SECRET).unlink()
            make(folder / intake.SECRET)
        return plant
    own = secrets.token_hex(64)
    hub_class(tmp_path / "course", {"s001": secret(lambda p: p.write_bytes(b"")),
                                    "s002": secret(lambda p: p.write_bytes(b"\xff\xfe not utf-8")),
                                    "s003": secret(Path.mkdir), "s004": secret(lambda p: p.write_text(own + "\n")),
                                    "s005": secret(lambda p: None), "s006": secret(lambda p: p.write_text(own))})
    intake.import_submissions(tmp_path / "course" / "submitted", tmp_path / "course", [LAB])
    taken = tmp_path / "course" / intake.EXCHANGE_INTAKE
    fresh = {(taken / s / LAB.id / intake.SECRET).read_text() for s in ("s001", "s002", "s003", "s004", "s005")}
    assert len(fresh) == 5 and all(re.fullmatch("[0-9a-f]{128}", text) for text in fresh) and own not in fresh
    for student in ("s001", "s002", "s003", "s004", "s005"):
        assert ("submission_secret.txt is not one that nbgrader's submit writes, so the grader gave it a new one: the "
                f"student cannot fetch this page with fetch_feedback; send it to them from feedback/{student}/{LAB.id}/."
                ) in notes_of(taken / student / LAB.id / LAB.notebook_name)
    assert (taken / "s006" / LAB.id / intake.SECRET).read_text() == own
    assert notes_of(taken / "s006" / LAB.id / LAB.notebook_name) == ""


def test_a_hub_username_with_an_at_sign_is_a_student_id(tmp_path):
    """Adversarial review: a hub's e-mail-like usernames were skipped as "not a student id". `@` is allowed after
    the first character, which stays a letter or a digit (no spreadsheet formula: tests/test_csv_cells.py)."""
    hub_class(tmp_path / "course", {"ann@uni.example": lambda _: None, "@SUM(A1)": lambda _: None})
    submitted = tmp_path / "course" / "submitted"
    assert intake.import_submissions(submitted, tmp_path / "course", [LAB]) == {LAB.id: ["ann@uni.example"]}
    assert tag(tmp_path / "course" / intake.EXCHANGE_INTAKE / "ann@uni.example" / LAB.id / LAB.notebook_name
               ) == "ann@uni.example"
    [line] = intake.not_student_ids(submitted, [LAB])
    assert line.startswith(f"The folder {str(submitted / '@SUM(A1)')!r} is not named by a student id")


def test_a_student_list_mapping_one_name_twice_is_refused(download, tmp_path):
    zip_path, _ = download
    students = tmp_path / "twice.csv"
    students.write_text("lms_name,student_id\nalice,s001\nalice,s009\n")
    with pytest.raises(IntakeError, match="'alice' is mapped to both s001 and s009"):
        collect(LAB, zip_path, students, tmp_path / "out")


def test_plain_nbgrader_zip_collect_uses_the_collector(download, tmp_path):
    """`nbgrader zip_collect` with our collector, as README shows it, into a course's submitted/."""
    zip_path, students = download
    course = tmp_path / "course"
    archive = course / "downloaded" / LAB.id / "archive"
    archive.mkdir(parents=True)
    (archive / zip_path.name).write_bytes(zip_path.read_bytes())
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    subprocess.run([sys.executable, "-m", "nbgrader", "zip_collect", LAB.id,
                    "--collector=autograder.pipeline.collect.StudentIdCollector",
                    "--extractor=autograder.pipeline.collect.SafeExtractor",
                    f"--StudentIdCollector.students_file={students}",
                    f"--StudentIdCollector.named_regexp={TIMED_PATTERN}"],
                   cwd=course, env=env, check=True, capture_output=True)
    assert sorted(p.name for p in (course / "submitted").iterdir()) == ["s001", "s002", "s003"]
    assert tag(course / "submitted/s001/train-kf/train-kf.ipynb") == "alice-new"


def test_grade_skips_a_folder_not_named_by_a_student_id_and_grades_the_rest(tmp_path, monkeypatch, capsys):
    """`=2+5` (a formula in a spreadsheet) and `-rm` are listed on the terminal and never reach the
    gradebook; s001 beside them is graded. Grading itself is stubbed: only the intake runs."""
    klass = tmp_path / "class"
    for student in ("=2+5", "s001", "-rm"):
        submissions.write(submissions.solved(LAB), klass, student, LAB)
    seen = {}
    monkeypatch.setattr(grading, "check_reference_available", lambda labs: None)
    monkeypatch.setattr(grading, "set_up", lambda labs, workdir, by_lab: seen.setdefault("registered", by_lab))
    def autograde(by_lab, workdir, jobs=None, submitted=intake.SUBMITTED):
        given = {(s, lab_id) for lab_id, students in seen.setdefault("graded", by_lab).items() for s in students}
        return dict.fromkeys(by_lab, ""), given, given
    monkeypatch.setattr(grading, "autograde", autograde)
    monkeypatch.setattr(grading, "read_grades", lambda workdir, labs, students=None: [])
    grading.grade(klass, tmp_path / "course", tmp_path / "grades.csv", jobs=1)
    assert seen == {"registered": {"train-kf": ["s001"]}, "graded": {"train-kf": ["s001"]}}
    assert sorted(p.name for p in (tmp_path / "course/submitted").iterdir()) == ["s001"]
    printed = capsys.readouterr().out
    for name in ("-rm", "=2+5"):
        assert (f"Skipped: The folder {str(klass / name)!r} is not named by a student id (letters, digits, _ . @ -, "
                "beginning with a letter or a digit); it was not graded.") in printed
    assert "Not graded: 2 folders not named by a student id (listed above)." in printed


def test_every_path_in_the_report_is_shown_quoted_if_it_holds_a_control_character():
    """A file name with an escape sequence (here: up a line, erase it) is quoted in every line of
    the report, the superseded and renamed lines too, so that it cannot act on the terminal."""
    from autograder.pipeline.collect import IntakeReport
    evil = "bob_\x1b[1A\x1b[2K.ipynb"
    report = IntakeReport("train-kf", ["s002"], [(evil, "not a notebook")], [(evil, "s002")], [], [(evil, "s002")],
                          [(evil, "bob (s002)", "it is a symbolic link")])
    lines = report.lines()
    assert len(lines) == 5 and not any("\x1b" in line for line in lines)
    assert all(repr(evil) in line for line in lines[1:])


def test_a_notebook_holding_text_no_file_can_store_is_graded_with_a_note(tmp_path):
    """Adversarial review of issue 31: a lone surrogate in a cell (valid JSON, and nbformat validates it) stopped
    `grade` for the whole class when intake wrote the notebook. It is replaced, and the note says so."""
    from autograder.pipeline.restore import grader_notes

    nb = submissions.solved(LAB)
    nb.cells.append(nbformat.v4.new_markdown_cell("my note \ud800 here"))
    folder = tmp_path / "subs" / "s001" / LAB.id
    folder.mkdir(parents=True)
    (folder / LAB.notebook_name).write_text(nbformat.writes(nb).replace("\ud800", "\\ud800"))
    intake.import_submissions(tmp_path / "subs", tmp_path / "course", [LAB])
    taken = nbformat.read(tmp_path / "course" / "submitted" / "s001" / LAB.id / LAB.notebook_name, as_version=4)
    assert taken.cells[-1].source == "my note \ufffd here"
    assert any("not valid Unicode" in note.text for note in grader_notes(taken))


def hex_secret(student: str) -> str:
    """A submission_secret.txt of nbgrader's form (128 hex digits), the same for the same student."""
    return student.encode().hex().ljust(128, "0")


def files_under(folder) -> dict[str, bytes]:
    """Relative path -> bytes of every file beneath ``folder``."""
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_the_courses_own_submitted_folder_is_left_as_collected_and_repaired_in_copies(tmp_path):
    """Issue 36: on a hub, `grade submitted` deleted nbgrader's submission_secret.txt from what `collect` left
    (release_feedback then failed) and rewrote the collected notebook in place. s001 submitted under another name,
    with a file of their own; s002 a file that is no notebook. submitted/ stays byte for byte as collected, and the
    copies that autograde reads (intake/) hold the repaired notebook, the time and the secret."""
    from autograder.pipeline.restore import grader_notes

    course = tmp_path / "course"
    for student, name, text in (("s001", "my work.ipynb", notebook("s001")), ("s002", LAB.notebook_name, '{"cells": [')):
        folder = course / "submitted" / student / LAB.id
        folder.mkdir(parents=True)
        (folder / name).write_text(text)
        (folder / "timestamp.txt").write_text("2026-10-09 10:00:00.000000 UTC")
        (folder / intake.SECRET).write_text(hex_secret(student))
    (course / "submitted/s001" / LAB.id / "scratch.py").write_text("x = 1\n")
    collected = files_under(course / "submitted")

    assert intake.graded_from(course / "submitted", course) == intake.EXCHANGE_INTAKE
    assert intake.import_submissions(course / "submitted", course, [LAB]) == {LAB.id: ["s001", "s002"]}
    assert files_under(course / "submitted") == collected
    taken = course / intake.EXCHANGE_INTAKE
    for student in ("s001", "s002"):
        assert sorted(files_under(taken / student / LAB.id)) == [intake.SECRET, "timestamp.txt", LAB.notebook_name]
        assert (taken / student / LAB.id / intake.SECRET).read_text() == hex_secret(student)
    assert tag(taken / "s001" / LAB.id / LAB.notebook_name) == "s001"
    [renamed] = grader_notes(nbformat.read(taken / "s001" / LAB.id / LAB.notebook_name, as_version=4))
    assert "submitted as my work.ipynb" in renamed.text
    [unreadable] = grader_notes(nbformat.read(taken / "s002" / LAB.id / LAB.notebook_name, as_version=4))
    assert "could not be read as a notebook" in unreadable.text


def test_an_lms_download_keeps_the_submission_secret_that_collect_left_in_submitted(tmp_path):
    """SUBMISSIONS elsewhere replaces the notebook in submitted/ and drops stale files, but nbgrader's
    submission_secret.txt stays there, for release_feedback; one that SUBMISSIONS holds is taken in too."""
    course = tmp_path / "course"
    for student in ("s001", "s002"):
        (course / "submitted" / student / LAB.id).mkdir(parents=True)
        (course / "submitted" / student / LAB.id / intake.SECRET).write_text("from-collect")
        (course / "submitted" / student / LAB.id / "stale.txt").write_text("old")
        (tmp_path / "subs" / student / LAB.id).mkdir(parents=True)
        (tmp_path / "subs" / student / LAB.id / LAB.notebook_name).write_text(notebook(student))
    (tmp_path / "subs/s002" / LAB.id / intake.SECRET).write_text(hex_secret("s002"))

    assert intake.graded_from(tmp_path / "subs", course) == intake.SUBMITTED
    intake.import_submissions(tmp_path / "subs", course, [LAB])
    for student, secret in (("s001", "from-collect"), ("s002", hex_secret("s002"))):
        folder = course / "submitted" / student / LAB.id
        assert sorted(p.name for p in folder.iterdir()) == [intake.SECRET, LAB.notebook_name]
        assert (folder / intake.SECRET).read_text() == secret and tag(folder / LAB.notebook_name) == student
    assert not (course / intake.EXCHANGE_INTAKE).exists()

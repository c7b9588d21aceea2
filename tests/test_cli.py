"""The instructor's command line and what it prints: every subcommand and argument explains itself,
--jobs defaults to the number of cores, `labs` names each blank, and the grading table fits a
100-column terminal with whole words, each lost cell once."""

from __future__ import annotations

import argparse
import os
import re


from autograder import cells, default_jobs
from autograder.pipeline import grading, table
from autograder.__main__ import build_parser
from autograder.pipeline.grading import GradeRow
from autograder.pipeline.restore import GraderNote, NoteKind
from autograder.authoring.inventory import print_inventory
from autograder.labs import Lab


def _subcommands(parser: argparse.ArgumentParser) -> dict[str, tuple[argparse.ArgumentParser, str | None]]:
    """Subcommand name -> (its parser, its help text)."""
    [sub] = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    helps = {choice.dest: choice.help for choice in sub._choices_actions}
    return {name: (p, helps.get(name)) for name, p in sub.choices.items()}


def test_every_subcommand_and_argument_has_a_help_text():
    missing = []
    for name, (parser, help_text) in _subcommands(build_parser()).items():
        if not help_text:
            missing.append(name)
        missing += [f"{name} {action.dest}" for action in parser._actions
                    if not isinstance(action, argparse._HelpAction) and not (action.help or "").strip()]
    assert missing == [], f"no help text: {missing}"
    assert len(_subcommands(build_parser())) >= 8


def test_jobs_defaults_to_the_number_of_cores_everywhere():
    cores = os.cpu_count() or 1
    assert default_jobs() == cores
    found = {name: next(a.default for a in parser._actions if a.dest == "jobs")
             for name, (parser, _) in _subcommands(build_parser()).items() if any(a.dest == "jobs" for a in parser._actions)}
    assert found.keys() >= {"grade", "demo"}
    assert found == dict.fromkeys(found, cores)
    # the library's own default (None) means the same
    import inspect
    assert inspect.signature(grading.grade).parameters["jobs"].default is None
    assert inspect.signature(grading.autograde).parameters["jobs"].default is None


def test_labs_lists_each_blank_by_name(capsys):
    lab = Lab("train-kf")
    print_inventory([lab])
    out = capsys.readouterr().out
    blanks = cells.blank_names(cells.read(lab.source_notebook))
    block = out.split(f"The blanks of {lab.id}", 1)[1].split("Claims that", 1)[0]
    listed = [line.split()[0] for line in block.splitlines()[1:] if line.strip()]
    assert listed == blanks
    assert max(len(line) for line in out.splitlines()) <= 100


LONG = ("AssertionError: kupdate: the analysis differs from the reference on 3 of 5 random cases; the largest "
        "difference is 0.381 in the covariance, which usually means the gain is applied to the wrong residual "
        "or the covariance update leaves out a term. Check the Joseph form line by line against equation (12).")


def _row(student: str, reasons: dict[str, str], lost: list[str], notes: tuple[GraderNote, ...] = ()) -> GradeRow:
    names = ["test_a", "test_b", "test_c", "test_d"]
    return GradeRow(student, "nonlinear-filters", {n: 0.0 if n in lost else 2.0 for n in names}, dict.fromkeys(names, 2.0),
                    frozenset(names), notes=notes, reasons=reasons)


DETAIL = re.compile(r" {4}( {2})?\S")
"""A line of the table under a row: a note or a lost cell, or its continuation."""


def _details(lines: list[str], student: str) -> list[str]:
    """The detail lines under ``student``'s row (after its continuation line, for a long name)."""
    at = next(i for i, line in enumerate(lines) if line.startswith(student)) + 1
    if not DETAIL.match(lines[at]) and lines[at].startswith(" "):
        at += 1
    end = next((i for i in range(at, len(lines)) if not DETAIL.match(lines[i])), len(lines))
    return lines[at:end]


def test_the_table_shows_a_late_penalty_and_the_total_that_grades_csv_has():
    """The summary said "alice 9/9 full marks" while grades.csv had late_penalty 4.5 and total 4.5."""
    late = GradeRow("alice", "train-kf", {"test_a": 9.0}, {"test_a": 9.0}, frozenset({"test_a"}), late_penalty=4.5)
    lines = _details(table.format_table([late], width=100).splitlines(), "alice")
    assert lines == ["    Late: a penalty of 4.5 points, so its total is 4.5 (grades.csv's total)."], lines


def test_a_late_submissions_own_row_gives_the_total_that_grades_csv_has():
    """Issue 36: the row itself still read "alice  train-kf  9/9  full marks", the penalty only on the line below."""
    late = GradeRow("alice", "train-kf", {"test_a": 9.0}, {"test_a": 9.0}, frozenset({"test_a"}), late_penalty=4.5)
    on_time = GradeRow("bob", "train-kf", {"test_a": 9.0}, {"test_a": 9.0}, frozenset({"test_a"}))
    rows = [line.split() for line in table.format_table([late, on_time], width=100).splitlines()
            if line.startswith(("alice", "bob"))]
    assert rows == [["alice", "train-kf", "9/9", "full", "marks;", "late,", "total", "4.5"],
                    ["bob", "train-kf", "9/9", "full", "marks"]], rows


def test_the_table_prints_no_terminal_control_from_a_submissions_message():
    """Adversarial review: a blank that raised an error whose message held escape sequences (cursor up,
    erase line, window title, clipboard, hyperlink) had them printed raw, which can overprint rows."""
    hostile = "ValueError: x\x1b[1A\x1b[2Kalice 9/9 full marks\x1b]0;owned\x07\x1b]52;c;cm0gLXJm\x07\x9b2J\x1b]8;;http://x\x1b\\ok\rz"
    text = table.format_table([_row("mallory", {"test_a": hostile}, ["test_a"])], width=100)
    assert not re.search(r"[\x00-\x09\x0b-\x1f\x7f-\x9f]", text), repr(text)
    assert "alice 9/9 full marks" in text, "the words stay, as plain text"


def test_the_table_fits_100_columns_with_whole_words_and_each_lost_cell_once():
    rows = [
        _row("a-student-with-a-very-long-identifier-from-the-lms-export", {"test_a": LONG}, ["test_a"]),
        _row("blank", dict.fromkeys(["test_a", "test_b", "test_c", "test_d"], "NotWrittenYet: You have not written this function yet."),
             ["test_a", "test_b", "test_c", "test_d"]),
        _row("solved", {}, []),
        _row("noreason", {}, ["test_c"], notes=(GraderNote(NoteKind.CHANGE, "It was submitted as train (1).ipynb and graded as train-kf.ipynb."),)),
    ]
    text = table.format_table(rows, {"nonlinear-filters": ["unreadable"]}, width=100)
    lines = text.splitlines()
    assert max(len(line) for line in lines) <= 100, max(lines, key=len)
    words = set(re.findall(r"\S+", LONG + " NotWrittenYet: You have not written this function yet. "
                                         "It was submitted as train (1).ipynb and graded as train-kf.ipynb. no reason was recorded"))
    for line in lines[2:]:
        if DETAIL.match(line):
            shown = line.split()
            if shown[-1] == "...":
                shown = shown[:-1]
            stray = [w.rstrip(",") for w in shown if w.rstrip(",") not in words and not w.startswith("test_")]
            assert stray == [], f"cut words {stray} in {line!r}"
    # each lost cell once: the blank's four cells share one line, the long reason is cut with an ellipsis
    for student, lost in (("blank", ["test_a", "test_b", "test_c", "test_d"]), ("a-student", ["test_a"]), ("noreason", ["test_c"])):
        details = _details(lines, student)
        for cell in lost:
            assert sum(len(re.findall(rf"\b{cell}\b", line)) for line in details) == 1, (student, cell, details)
    assert lines[2] == "a-student-with-a-very-long-identifier-from-the-lms-export"
    assert "6/8" in text and "lost 1 of 4 cells" in text and "full marks" in text and "no reason was recorded" in text
    assert any(line.endswith(" ...") for line in lines), "the long reason ends in an ellipsis"
    assert "unreadable" in text and "not graded" in text


def test_the_quick_demo_class_and_its_check(tmp_path):
    """The default demo class of one lab: blank, solved, two mistakes in different blanks, one cheat
    and one fault, each with what grading must make of it; a row that differs is reported."""
    from autograder.catalogues import demo
    from autograder.catalogues.synthetic_class import Outcome

    lab = Lab("train-kf")
    expected = demo.write_demo_class([lab], tmp_path / "class")
    kinds = sorted(outcome.kind for outcome in expected.values())
    assert kinds == sorted(["blank", "solved", "mistake", "mistake", "cheat", "fault"])
    mistakes = [o.zero for o in expected.values() if o.kind == "mistake"]
    assert len(set(mistakes)) == 2, "the two mistakes are in different blanks"
    assert sorted(p.parent.parent.name for p in (tmp_path / "class").glob(f"*/{lab.id}/*.ipynb")) == sorted(s for s, _ in expected)
    assert (tmp_path / "class").exists() and all(key[1] == lab.id for key in expected)

    points = {c: 2.0 for c in ("test_a", "test_b")}
    solved = GradeRow("solved", lab.id, dict(points), dict(points), frozenset(points))
    assert demo.unexpected([solved], {("solved", lab.id): Outcome("solved", "solved", (), True, False)}) == []
    wrong = GradeRow("solved", lab.id, {"test_a": 0.0, "test_b": 2.0}, dict(points), frozenset(points),
                     reasons={"test_a": "AssertionError: no"})
    assert demo.unexpected([wrong], {("solved", lab.id): Outcome("solved", "solved", (), True, False)}) == [
        "train-kf: solved: test_a lost marks (AssertionError: no)"]
    assert demo.unexpected([], {("blank", lab.id): Outcome("blank", "blank", None, False, False)}) == [
        "train-kf: blank was not graded"]


def test_the_demo_closes_with_a_verdict_and_where_to_look(tmp_path, monkeypatch, capsys):
    """run_demo's own output around the grading (grading itself replaced: it grades nothing here,
    so every row is missing and the verdict must say so)."""
    from autograder.catalogues import demo

    monkeypatch.setattr(demo, "all_labs", lambda: [Lab("train-kf")])
    monkeypatch.setattr(demo.grading, "grade", lambda *args, **kwargs: grading.Graded([], [], []))
    assert demo.run_demo(tmp_path, 1) is False
    out = capsys.readouterr().out
    assert " ".join(out.split()).startswith("Demo class: 6 submissions of 1 lab from 6 students in ")
    assert "Not as expected: 6 differences between the grades and the catalogues:" in out
    assert "train-kf: solved was not graded" in out
    for what in ("grades.csv", "/feedback/", "Nbgrader > Formgrader > Manual Grading", "autograder feedback --workdir",
                 "demo --full", "The class report", f"{tmp_path / 'course' / 'report' / 'train-kf.html'}\n"):
        assert what in out, what
    long = [line for line in out.splitlines() if len(line) > 100 and not line.startswith(" " * 6)
            and not (len(line.split()) == 1 and "/" in line)]
    assert long == [], "lines wider than 100 columns (other than a path or a command to copy)"
    whole = len(demo.write_demo_class([Lab("train-kf")], tmp_path / "whole", full=True))
    assert f"The whole catalogue ({whole} submissions, {whole / 6:.0f} times as many as here):" in " ".join(out.split())
    monkeypatch.setattr(demo, "unexpected", lambda rows, expected: [])
    assert demo.run_demo(tmp_path, 1) is True
    assert "All 6 rows came out as expected" in capsys.readouterr().out

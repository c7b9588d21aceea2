"""Every CSV the kit writes is safe to open in a spreadsheet: a cell that begins with = + - @, a tab
or a carriage return gets a leading ' (OWASP's rule on CSV injection); numbers stay numbers, and
honest rows read back as they were written."""

import csv
import re

import pytest

from autograder.csv_cells import cell
from autograder.pipeline.restore import GraderNote, NoteKind
from autograder.integrity import similarity
from autograder.labs import ROOT
from autograder.pipeline import grades

DANGEROUS = ["=2+5", "+cmd|' /C calc'!A0", "-2+3", "@SUM(A1:A9)", "\t=1+1", "\r=1+1"]


def read(path) -> list[dict[str, str]]:
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def row(student: str, notes: tuple[str, ...] = (), score: float = 1.5, penalty: float = 0.0) -> grades.GradeRow:
    return grades.GradeRow(student, "train-kf", {"test_predict": score, "test_update": None},
                           {"test_predict": 2.0, "test_update": 2.0}, frozenset({"test_predict"}), penalty,
                           tuple(GraderNote(NoteKind.CHANGE, note) for note in notes))


@pytest.mark.parametrize("text", DANGEROUS)
def test_text_that_a_spreadsheet_reads_as_a_formula_is_quoted(text):
    assert cell(text) == "'" + text


@pytest.mark.parametrize("value", ["-0.5", "-1e-05", "+3", "0", "1.5", "s001", "", 2, -0.5, "train-kf", "a=b"])
def test_numbers_and_plain_text_are_kept(value):
    assert cell(value) == value


def test_grades_csv_neutralises_student_ids_and_notes(tmp_path):
    rows = [row(text, (f"{text} was here",)) for text in DANGEROUS] + [row("s009", ("=HYPERLINK(\"http://x\")",))]
    honest = row("s001", ("It was submitted as bob.ipynb and graded as train-kf.ipynb.",), score=-0.5, penalty=0.2)
    grades.write_csv([*rows, honest], tmp_path / "grades.csv")
    records = read(tmp_path / "grades.csv")
    assert [r["student"] for r in records] == ["'" + text for text in DANGEROUS] + ["s009", "s001"]
    assert records[-2]["notes"] == "'=HYPERLINK(\"http://x\")"
    assert records[-1] == {"student": "s001", "lab": "train-kf", "test_predict": "-0.5", "test_update": "",
                           "late_penalty": "0.2", "total": "0", "max_score": "4", "flagged": "",
                           "notes": "It was submitted as bob.ipynb and graded as train-kf.ipynb."}
    assert float(records[-1]["test_predict"]) == -0.5


def test_the_similarity_csv_neutralises_student_ids(tmp_path):
    pairs = [similarity.Pair("train-kf", "predict", text, "s002", 0.9, 40, False) for text in DANGEROUS]
    honest = similarity.Pair("train-kf", "predict", "s001", "s002", 1.0, 12, True)
    similarity.write_csv(similarity.Report([*pairs, honest], [], [], []), tmp_path / "pairs.csv")
    records = read(tmp_path / "pairs.csv")
    assert [r["student_a"] for r in records] == ["'" + text for text in DANGEROUS] + ["s001"]
    assert records[-1] == {"lab": "train-kf", "blank": "predict", "student_a": "s001", "student_b": "s002",
                           "score": "1", "tokens": "12", "model_answer": "yes"}


def test_every_csv_writer_of_the_kit_goes_through_csv_cells():
    writers = [f"{path.relative_to(ROOT)}: {line.strip()}" for path in sorted((ROOT / "autograder").rglob("*.py"))
               if path.name != "csv_cells.py"
               for line in path.read_text().splitlines() if re.search(r"\bcsv\.(writer|DictWriter)\(", line)]
    assert not writers, "write CSVs with autograder.csv_cells.writer:\n" + "\n".join(writers)


def test_control_characters_are_dropped_so_the_file_is_safe_on_a_terminal():
    """Adversarial review of issue 31: an escape sequence from a student's error message reached grades.csv."""
    assert cell("ZeroDivisionError: \x1b]0;pwned\x07\x1b[2Jx\ty") == "ZeroDivisionError: ]0;pwned[2Jx\ty"
    assert cell("\x1b=1+1") == "'=1+1"

"""The class report (autograder/pipeline/class_report.py): every count equals the number the
synthetic class was built with; the diagnosis is the grader's data, which a submission cannot
forge and a regrade replaces; the page is self-contained, runs no script and shows a submission's
text as text."""

import csv
import re
import shutil
from datetime import timedelta

import nbformat
import pytest

from autograder import cells
from autograder.catalogues import cheats, faults, submissions
from autograder.catalogues.mistakes import Mistake, catalogue
from autograder.authoring import visible_checks
from autograder.catalogues.synthetic_class import cheat_outcome
from autograder.labs import get_lab
from autograder.pipeline import class_report, grading, late, verdicts
from autograder.hidden_tests.case_kinds import wrong_only
from autograder.pipeline.grades import GradeRow
from autograder.pipeline.restore import GraderNote, NoteKind
from lab_code import define, hidden_tests
from over_labs import about
from course.checks import NOT_WRITTEN

LAB = get_lab("train-kf")
MISTAKES = {"no-Q": 3, "innovation-sign": 2}
"""Catalogued mistake -> how many students make it."""
CHEAT, FAULT = cheats.get("import-reference"), faults.get("kernel-dies")
UNCATALOGUED = Mistake("nees", "divided-by-n-squared", "divides e^T B^-1 e by n^2", "return np.sum(errors * scaled, axis=1)",
                       "return np.sum(errors * scaled, axis=1) / errors.shape[1] ** 2")
"""A mistake no catalogue holds, right on the hidden cases with n = 1 alone: lost another way, wrong on one kind of case."""
pytestmark = about(LAB)


def mistake(slug: str):
    [found] = [m for m in catalogue(LAB) if m.slug == slug]
    return found


def write_class(folder) -> dict:
    """blank, 2 solved, each of MISTAKES as often as it says, UNCATALOGUED, one cheat, one fault in the
    first blank, and one solved notebook submitted two days late: what the report must count."""
    submissions.write(cells.read(LAB.release_notebook), folder, "blank", LAB)
    for k in (1, 2):
        nb = submissions.solved(LAB)
        if k == 1:  # a failed visible check the submission claims is not the grader's record
            [check] = [c for c in nb.cells if cells.is_visible_check(c) and cells.grade_id(c) == "check_nees"]
            check.metadata[verdicts.VISIBLE_CHECK_KEY] = True
        submissions.write(nb, folder, f"solved-{k}", LAB)
    for slug, times in MISTAKES.items():
        for k in range(times):
            nb = submissions.with_mistake(LAB, mistake(slug))
            if slug == "no-Q" and k == 0:  # a diagnosis the submission forges is not the grader's
                [test] = [c for c in nb.cells if cells.is_autograded_test(c) and cells.grade_id(c) == "test_nees"]
                test.metadata[verdicts.DIAGNOSIS_KEY] = "root"
            if slug == "innovation-sign" and k == 1:  # nor is a kind of case alone wrong
                [test] = [c for c in nb.cells if cells.is_autograded_test(c) and cells.grade_id(c) == "test_kupdate"]
                test.metadata[verdicts.WRONG_ONLY_KEY] = "a full R"
            submissions.write(nb, folder, f"{slug}-{k}", LAB)
    submissions.write(submissions.with_mistake(LAB, UNCATALOGUED), folder, "uncatalogued", LAB)
    submissions.write(CHEAT.notebook(LAB), folder, CHEAT.name, LAB)
    first = LAB.blanks()[0]
    fault = faults.write_fault(FAULT, LAB, first, folder)
    path = submissions.write(submissions.solved(LAB), folder, "late", LAB)
    due = late.read_due_dates(late.DUE_DATES)[LAB.id]
    (path.parent / "timestamp.txt").write_text((due + timedelta(days=2)).isoformat())
    return {"first": first, "fault": fault, "gamed": cheat_outcome(LAB, CHEAT).zero}


def read(path) -> list[dict]:
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def counted(folder) -> dict[tuple[str, str, str], int]:
    """(cell, what, detail) -> count, from the report's CSV."""
    return {(r["cell"], r["what"], r["detail"]): int(r["count"]) for r in read(folder / f"{LAB.id}.csv")}


def behind(folder) -> dict[tuple[str, str, str], set[str]]:
    """(cell, what, detail) -> the students behind that count, from the report's students file."""
    found: dict[tuple[str, str, str], set[str]] = {}
    for r in read(folder / f"{LAB.id}-students.csv"):
        found.setdefault((r["cell"], r["what"], r["detail"]), set()).add(r["student"])
    return found


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    root = tmp_path_factory.mktemp("class-report")
    built = write_class(root / "class")
    rows = grading.grade(root / "class", root / "course", jobs=2).rows
    return root, built, rows


def test_every_count_is_the_number_the_class_was_built_with(graded):
    root, built, rows = graded
    found = counted(root / "course" / "report")
    students = len(rows)
    assert students == 2 + sum(MISTAKES.values()) + 5 and found["", class_report.SUBMITTED, ""] == students
    tests = [c for c in rows[0].cells if c in rows[0].autograded]
    gamed = set(tests if built["gamed"] is None else built["gamed"])
    for cell in tests:
        blank = cell.removeprefix("test_")
        wrong = {m: n for m, n in MISTAKES.items() if mistake(m).blank == blank}
        other = (cell == f"test_{built['first']}") + (cell in gamed) + (cell == f"test_{UNCATALOGUED.blank}")
        assert found[cell, class_report.NOT_WRITTEN, ""] == 1, cell
        assert found[cell, class_report.FULL, ""] == students - 1 - sum(wrong.values()) - other, cell
        assert {d: n for (c, what, d), n in found.items() if c == cell and what == class_report.MISTAKE} == wrong, cell
        assert sum(n for (c, what, _), n in found.items() if c == cell and what == class_report.OTHER) == other, cell
        # the cheat's blanks: lost in a flagged submission, said so rather than by the zeroed cell's error
        assert found.get((cell, class_report.OTHER, class_report.FLAGGED_DETAIL), 0) == (cell in gamed), cell
        # the uncatalogued mistake: by the kind of case that alone it is wrong on, as its hidden test says here
        wrong_on = class_report.WRONG_ONLY.format(uncatalogued_wrong_on())
        assert found.get((cell, class_report.OTHER, wrong_on), 0) == (cell == f"test_{UNCATALOGUED.blank}"), cell
    assert found["", class_report.FLAGGED, ""] == 1 and found["", class_report.LATE, ""] == 1
    assert found["", class_report.FAULTED, ""] == 1
    scores = sum(n for (c, what, _), n in found.items() if what == class_report.SCORE)
    assert scores == students
    # nbgrader scores an unchanged written answer 0 itself; every other written answer waits for a hand grade
    waiting = {c: n for (c, what, _), n in found.items() if what == class_report.WAITING}
    assert waiting and set(waiting.values()) == {students - 1}


def test_the_students_file_names_the_students_behind_each_count(graded):
    root, built, _ = graded
    by_count = behind(root / "course" / "report")
    assert by_count["test_predict", class_report.MISTAKE, "no-Q"] == {"no-Q-0", "no-Q-1", "no-Q-2"}
    assert by_count["test_kupdate", class_report.MISTAKE, "innovation-sign"] == {"innovation-sign-0", "innovation-sign-1"}
    assert by_count["", class_report.FLAGGED, ""] == {CHEAT.name}
    assert by_count["", class_report.FAULTED, ""] == {built["fault"]}
    assert by_count["", class_report.LATE, ""] == {"late"}


def uncatalogued_wrong_on() -> str:
    """The kind of case that alone UNCATALOGUED is wrong on, from its hidden test run here."""
    model = cells.model_answers(cells.read(LAB.source_notebook))[UNCATALOGUED.blank]
    with pytest.raises(AssertionError) as caught:
        getattr(hidden_tests(LAB), f"check_{UNCATALOGUED.blank}")(define(LAB, UNCATALOGUED.apply(model), UNCATALOGUED.blank))
    assert wrong_only(caught.value) is not None
    return wrong_only(caught.value)


def test_the_diagnosis_is_the_graders_data(graded):
    """Recorded beside the verdict for exactly the diagnosed cells; the one a submission brought is gone.
    So is the kind of case alone wrong, for every cell lost where the hidden test's cases split so."""
    _, _, rows = graded
    diagnosed = {row.student: row.diagnosed for row in rows if row.diagnosed}
    assert diagnosed == {**{f"no-Q-{k}": {"test_predict": "no-Q"} for k in range(3)},
                         **{f"innovation-sign-{k}": {"test_kupdate": "innovation-sign"} for k in range(2)}}
    wrong_on = {row.student: row.wrong_only for row in rows if row.wrong_only}
    assert wrong_on == {"uncatalogued": {f"test_{UNCATALOGUED.blank}": uncatalogued_wrong_on()}}


def test_the_page_is_self_contained_and_runs_no_script(graded):
    root, _, _ = graded
    page = (root / "course" / "report" / f"{LAB.id}.html").read_text()
    assert 'src="data:image/png;base64,' in page and mistake("no-Q").hint in page
    text = re.sub(r'"data:image/png;base64,[A-Za-z0-9+/=]*"', "", page)
    assert "<script" not in text.lower() and not re.search(r"(https?:)?//[a-z0-9]", text, re.I)
    assert (root / "course" / "report" / f"{LAB.id}.png").read_bytes().startswith(b"\x89PNG")
    assert "no-Q-0" not in page  # counts only: no student is named


def raising(blank: str) -> str:
    """An answer to ``blank`` whose function raises when called."""
    return f"def {blank}(*args, **kwargs):\n    raise RuntimeError('no answer in the grading kernel')\n"


def test_the_submissions_with_failing_visible_checks_are_counted(graded):
    """Per blank and per lab, as the solved notebook run here with each student's answers says
    (autograder/authoring/visible_checks.py); the blank, solved and late submissions fail none (an
    unwritten blank is counted as not written)."""
    root, built, rows = graded
    model = cells.model_answers(cells.read(LAB.source_notebook))
    answers = {f"{slug}-{k}": {mistake(slug).blank: mistake(slug).apply(model[mistake(slug).blank])}
               for slug, times in MISTAKES.items() for k in range(times)}
    answers["uncatalogued"] = {UNCATALOGUED.blank: UNCATALOGUED.apply(model[UNCATALOGUED.blank])}
    # in the grading kernel the cheat's import of the reference fails (the sandbox) and the fault's blank
    # kills its kernel: for the checks, each is a function that raises when called
    tests = [c for c in rows[0].cells if c in rows[0].autograded]
    gamed = tests if built["gamed"] is None else built["gamed"]
    answers[CHEAT.name] = {cell.removeprefix("test_"): raising(cell.removeprefix("test_")) for cell in gamed}
    answers[built["fault"]] = {built["first"]: raising(built["first"])}
    runs: dict[str, set[str]] = {}
    failing = {student: runs.setdefault(repr(sorted(given.items())), visible_checks.failing_checks(LAB, given))
               for student, given in answers.items()}
    found = counted(root / "course" / "report")
    for cell in tests:
        assert found[cell, class_report.VISIBLE_FAILED, ""] == sum(cell.removeprefix("test_") in f for f in failing.values()), cell
    by_count = behind(root / "course" / "report")
    assert by_count["", class_report.VISIBLE_FAILED, ""] == {student for student, f in failing.items() if f}
    assert found["", class_report.VISIBLE_FAILED, ""] == len(by_count["", class_report.VISIBLE_FAILED, ""]) > 0
    page = (root / "course" / "report" / f"{LAB.id}.html").read_text()
    assert page.count("visible checks failed") == len(tests) + 1
    # information only: the mistakes' students lose the points of their mistake's blank alone
    assert all(row.lost == [f"test_{mistake(row.student.rsplit('-', 1)[0]).blank}"] for row in rows
               if row.student in answers and row.student.rsplit("-", 1)[0] in MISTAKES)


def test_regrading_one_student_replaces_their_diagnosis(graded, tmp_path):
    root, _, _ = graded
    regrade = tmp_path / "regrade"
    submissions.write(submissions.solved(LAB), regrade, "no-Q-0", LAB)
    grading.grade(regrade, root / "course", jobs=1)
    found = counted(root / "course" / "report")
    assert found["test_predict", class_report.MISTAKE, "no-Q"] == MISTAKES["no-Q"] - 1


def test_the_page_groups_losses_by_the_kind_of_case_alone_wrong(tmp_path):
    """Without grading: two students wrong only on the cases with a full R, one by an error."""
    cell = "test_kupdate"
    rows = [GradeRow(f"s{k}", LAB.id, {cell: 0.0}, {cell: 2.0}, frozenset({cell}), reasons={cell: "AssertionError: x"},
                     wrong_only={cell: "a full R"} if k < 2 else {}) for k in range(3)]
    [page] = class_report.write_report(tmp_path, rows)
    assert counted(tmp_path / "report")[cell, class_report.OTHER, "wrong only on the cases with a full R"] == 2
    text = page.read_text()
    assert '<td class="sub">wrong only on the cases with a full R</td><td class="n">2</td>' in text
    assert '<td>lost another way</td><td class="n">3</td><td class="hint">AssertionError: 1</td>' in text


def test_a_submissions_text_is_escaped_on_the_page_and_neutralised_in_the_csv(tmp_path):
    """Without grading: a row whose failing error's name is markup, and a student id that is a formula."""
    hostile = "<img src=x onerror=alert(1)>"
    cell = f"test_{LAB.blanks()[0]}"
    row = GradeRow("=HYPERLINK(1)", LAB.id, {cell: 0.0}, {cell: 1.0}, frozenset({cell}),
                   reasons={cell: f"{hostile}: boom"})
    [page] = class_report.write_report(tmp_path, [row])
    text = page.read_text()
    assert hostile not in text and "&lt;img src=x onerror=alert(1)&gt;" in text
    students = (tmp_path / "report" / f"{LAB.id}-students.csv").read_text()
    assert "'=HYPERLINK(1)" in students and "\n=" not in students.replace("\r\n", "\n")
    shutil.rmtree(tmp_path / "report")


FAKE_STOP = '''
class _Shown:
    def __init__(self, name, text):
        self.name, self.text = name, text
    def _repr_html_(self):
        raise type(self.name, (Exception,), {})(self.text)
    def __repr__(self):
        return ""
_kit_validate = validate
def validate(f):
    if getattr(f, "__name__", "") == "kupdate":
        display(_Shown("CellTimeoutError", "fake"))
        return None
    return _kit_validate(f)
'''
"""What an adversarial review of issue 31 appended to kupdate's cell: a display that raises, so that the visible part of
kupdate's test cell shows an error named CellTimeoutError, which made the grader take the cell as stopped, skip its
hidden test and its diagnosis, and keep the kernel's errors in the test cell."""


def test_a_submission_cannot_hide_its_mistake_from_the_report(tmp_path):
    """The review's two routes, in one submission with a catalogued mistake in kupdate: the stub's text left as a comment
    (the blank was counted not written) and a faked stop (the hidden test was skipped). The grader still runs the hidden
    test and diagnoses the mistake, the blank counts as written, and the cell holds the grader's error alone."""
    nb = submissions.with_mistake(LAB, mistake("innovation-sign"))
    [cell] = [c for c in nb.cells if cells.is_code_answer(c) and cells.grade_id(c) == "kupdate"]
    cell.source = f"# {NOT_WRITTEN}\n{cell.source}\n{FAKE_STOP}"
    submissions.write(nb, tmp_path / "class", "s001", LAB)
    [row] = grading.grade(tmp_path / "class", tmp_path / "course", jobs=1).rows
    assert row.lost == ["test_kupdate"] and row.diagnosed == {"test_kupdate": "innovation-sign"}, (row.lost, row.reasons)
    assert "test_kupdate" not in row.not_written
    assert not any("ran for more than" in note.text for note in row.notes), row.notes
    graded = nbformat.read(tmp_path / "course" / "autograded" / "s001" / LAB.id / LAB.notebook_name, as_version=4)
    [test] = [c for c in graded.cells if cells.meta(c).get("grade_id") == "test_kupdate"]
    assert [o.ename for o in test.outputs if o.output_type == "error"] == ["AssertionError"], test.outputs


def test_only_what_the_grader_changed_counts_as_a_fault():
    """The review's count route: a file named 'x failed when the grader ran it.ipynb' kept its intake note out of
    the faulted count, when the report told execute.first_cause's note apart by its text. The report now reads
    each note's kind from the grader's metadata (restore.NoteKind): a cause or a flag is not a fault, whatever
    its text."""
    names = {"test_kupdate": 1.0}
    row = lambda *notes: GradeRow("s", LAB.id, names, names, frozenset(names), notes=notes)  # noqa: E731
    quoting = GraderNote(NoteKind.CHANGE, "It was submitted as x failed when the grader ran it (1).ipynb and graded.")
    cause = GraderNote(NoteKind.CAUSE, "Your cell kupdate failed when the grader ran it (ZeroDivisionError: x).")
    flag = GraderNote(NoteKind.FLAG, "Flagged for review: it reads the reference. It costs no points.")
    assert class_report.count_lab(LAB, [row(quoting)]).faulted == ("s",)
    assert class_report.count_lab(LAB, [row(cause, flag)]).faulted == ()


def test_a_blank_the_grader_did_not_find_as_its_stub_or_diagnosed_is_not_counted_as_not_written(tmp_path):
    """Adversarial reviews of issue 31: a student left the stub as released and bound kupdate, with a wrong answer,
    in a cell added below it (by def, then by import or match, which a reading of the cells missed); the report
    counted the blank "not written" and hid the mistake. A blank is not written only when the grader's hidden test
    called its stub; and the grader's diagnosis comes before anything read from the cells."""
    from autograder.pipeline.grades import _read_autograded

    nb = submissions.solved(LAB)
    [stub] = [c for c in cells.read(LAB.release_notebook).cells if cells.is_code_answer(c) and cells.grade_id(c) == "kupdate"]
    [answer] = [c for c in nb.cells if cells.is_code_answer(c) and cells.grade_id(c) == "kupdate"]
    answer.source = stub.source
    [test] = [c for c in nb.cells if cells.meta(c).get("grade_id") == "test_kupdate"]
    path = tmp_path / "graded.ipynb"
    for error, counted in ((f"{NOT_WRITTEN} It was raised on the case with a scalar state.", True),
                           ("the analysis differs from the reference", False)):
        ename = "NotImplementedError" if counted else "AssertionError"
        test.outputs = [nbformat.v4.new_output("error", ename=ename, evalue=error, traceback=[])]
        nbformat.write(nb, path)
        assert ("test_kupdate" in _read_autograded(path, LAB)[4]) is counted, error
    answer.source = "# I will do it later\n" + stub.source  # a final review: a stub with a comment is still the stub
    test.outputs = [nbformat.v4.new_output("error", ename="NotImplementedError", evalue=NOT_WRITTEN, traceback=[])]
    nbformat.write(nb, path)
    assert "test_kupdate" in _read_autograded(path, LAB)[4]
    names = {"test_kupdate": 2.0}
    row = GradeRow("s", LAB.id, {"test_kupdate": 0.0}, names, frozenset(names), not_written=frozenset(names),
                   diagnosed={"test_kupdate": "innovation-sign"})
    mistakes = {(m.blank, m.slug): m for m in catalogue(LAB)}
    assert class_report.outcome(row, "test_kupdate", mistakes) == (class_report.MISTAKE, "innovation-sign")

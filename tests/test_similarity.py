"""The similarity report: normalised answers (renamed variables, reformatting and comments do not
hide a copy), identical model answers listed as copies, independent correct answers not listed,
and no grade touched."""

import difflib

import nbformat
import numpy as np
import pytest
import scipy.linalg

import solutions.train_kf.hidden_tests as hidden
from autograder import cells
from autograder.integrity import similarity
from autograder.catalogues import submissions
from autograder.__main__ import main
from autograder.labs import get_lab
from autograder.catalogues.mistakes import catalogue

LAB = get_lab("train-kf")
MODEL = cells.model_answers(cells.read(LAB.source_notebook))

DISGUISED_KUPDATE = '''def kupdate(x_f, B_f, y, H, R):
    """My own update."""
    gain = gain_covariance_form(B_f, H, R)   # Kalman gain
    xa = x_f + gain @ (y -
                       H @ x_f)
    # covariance
    Ba = B_f - gain@H@B_f
    return (xa, Ba)
'''

INDEPENDENT = {
    "nees": '''def nees(errors, covariances):
    values = []
    for e, C in zip(errors, covariances):
        L = np.linalg.cholesky(C)
        z = np.linalg.solve(L, e)
        values.append(z @ z)
    return np.array(values)
''',
    "gain_information_form": '''def gain_information_form(B, H, R):
    Rinv = np.linalg.inv(R)
    P = np.linalg.inv(np.linalg.inv(B) + H.T @ Rinv @ H)
    return P @ H.T @ Rinv
''',
    "gain_covariance_form": '''def gain_covariance_form(B, H, R):
    innovation_cov = H.dot(B).dot(H.T) + R
    return B.dot(H.T).dot(np.linalg.inv(innovation_cov))
''',
    "process_noise": '''def process_noise(sigma, dt_min=1.0):
    dt = dt_min / 60
    G = np.array([[dt], [1.0]])
    return sigma ** 2 * (G @ G.T)
''',
    "predict": '''def predict(x, B, A, Q):
    return A.dot(x), A.dot(B).dot(A.T) + Q
''',
    "kupdate": '''def kupdate(x_f, B_f, y, H, R):
    S = H @ B_f @ H.T + R
    K = np.linalg.solve(S, H @ B_f).T
    innov = y - H @ x_f
    I = np.eye(len(x_f))
    return x_f + K @ innov, (I - K @ H) @ B_f
''',
    "run_filter": '''def run_filter(y, x0, B0, A, Q, H, R):
    estimates, covariances = [], []
    x, B = x0.copy(), B0.copy()
    for obs in y:
        x, B = predict(x, B, A, Q)
        x, B = kupdate(x, B, obs, H, R)
        estimates.append(x)
        covariances.append(B)
    return np.array(estimates), np.array(covariances)
''',
}
"""Correct answers written without looking at the model answers."""


def score(one: str, two: str, blank: str) -> float:
    a, b = (similarity.tokens(similarity.normalise_code(code, {blank})) for code in (one, two))
    return difflib.SequenceMatcher(None, a, b, autojunk=False).ratio()


def with_answers(answers: dict[str, str]) -> nbformat.NotebookNode:
    """The solved notebook with these answers in place of the model answers."""
    nb = submissions.solved(LAB)
    for cell in nb.cells:
        if cells.is_answer(cell) and cells.grade_id(cell) in answers:
            cell.source = answers[cells.grade_id(cell)]
    return nb


def test_renamed_variables_reformatting_and_comments_do_not_hide_a_copy():
    assert similarity.normalise_code(DISGUISED_KUPDATE, {"kupdate"}) == similarity.normalise_code(MODEL["kupdate"], {"kupdate"})
    assert score(DISGUISED_KUPDATE, MODEL["kupdate"], "kupdate") == 1.0
    raw = difflib.SequenceMatcher(None, DISGUISED_KUPDATE, MODEL["kupdate"], autojunk=False).ratio()
    assert raw < 0.7, "the raw text is far apart: only the normalisation shows the copy"
    # the blank's own name, globals, attributes and called functions are kept
    assert similarity.normalise_code(DISGUISED_KUPDATE, {"kupdate"}).startswith(
        "def kupdate(a0, a1, a2, a3, a4):\n    _ = gain_covariance_form(a1, a3, a4)\n")


def move(code: str, line: str, after: str) -> str:
    """``code`` with ``line`` moved to just after the line ``after``."""
    assert line in code and after in code
    moved = code.replace(line, "").replace(after, after + line)
    assert moved != code
    return moved


def test_a_copy_with_statements_moved_still_scores_above_the_threshold():
    run_filter = move(MODEL["run_filter"], "    T, n = y.shape[0], x0.shape[0]\n", "    x, B = x0, B0\n")
    kupdate = move(MODEL["kupdate"], "    x_a = x_f + K @ (y - H @ x_f)\n", "    B_a = B_f - K @ H @ B_f\n")
    assert similarity.THRESHOLD <= score(run_filter, MODEL["run_filter"], "run_filter") < 1.0
    assert similarity.THRESHOLD <= score(kupdate, MODEL["kupdate"], "kupdate") < 1.0


@pytest.mark.parametrize("blank", sorted(INDEPENDENT))
def test_independent_correct_answers_are_not_listed(blank):
    namespace = {"np": np, "scipy": scipy}
    exec(INDEPENDENT[blank], namespace)
    getattr(hidden, f"check_{blank}")(namespace[blank])  # a correct answer: the hidden tests pass
    assert score(INDEPENDENT[blank], MODEL[blank], blank) < similarity.THRESHOLD


@pytest.fixture
def class_dir(tmp_path):
    """A small class in an nbgrader course folder (submitted/): the model answers, two catalogued
    mistakes, the blank release, an independent student (who left the written answers blank), the
    model answers with kupdate disguised, a notebook that is not JSON, and an answer that is not
    Python."""
    mistakes = {m.student_id(LAB): m for m in catalogue(LAB) if m.slug in ("no-Q", "innovation-sign")}
    written = [cells.grade_id(c) for c in cells.read(LAB.release_notebook).cells if c.cell_type == "markdown" and cells.is_answer(c)]
    notebooks = {
        submissions.SOLVED: submissions.solved(LAB),
        submissions.BLANK: cells.read(LAB.release_notebook),
        "independent": with_answers({**INDEPENDENT, **{blank: similarity.TEXT_STUB for blank in written}}),
        "disguised": with_answers({"kupdate": DISGUISED_KUPDATE}),
        "broken": with_answers({"predict": "def predict(x, B, A, Q):\n    return A @ (x"}),
        **{student: submissions.with_mistake(LAB, m) for student, m in mistakes.items()},
    }
    for student, nb in notebooks.items():
        path = tmp_path / "submitted" / student / LAB.id / LAB.notebook_name
        path.parent.mkdir(parents=True)
        nbformat.write(nb, path)
    (tmp_path / "submitted" / "truncated" / LAB.id).mkdir(parents=True)
    (tmp_path / "submitted" / "truncated" / LAB.id / LAB.notebook_name).write_text('{"cells": [')
    return tmp_path


def test_report_lists_identical_model_answers_and_disguised_copies(class_dir):
    report = similarity.compare(class_dir, [LAB])
    pairs = {(p.blank, p.student_a, p.student_b): p for p in report.pairs}
    solved, no_q, sign = submissions.SOLVED, "train-kf_predict_no-Q", "train-kf_kupdate_innovation-sign"
    # identical model answers, code and written: every student who has them, grouped
    groups = {(g.blank, g.students): g.model_answer for g in report.groups}
    assert groups[("predict", ("disguised", solved, sign))] is True  # broken's predict is not Python
    assert groups[("kupdate", ("broken", "disguised", solved, no_q))] is True
    assert groups[("derivation_1", ("broken", "disguised", solved, sign, no_q))] is True
    assert pairs[("process_noise", solved, sign)].score == 1.0
    assert pairs[("kupdate", "disguised", solved)].score == 1.0 and pairs[("kupdate", "disguised", solved)].model_answer
    # a one-token mistake is still a near copy
    assert similarity.THRESHOLD <= pairs[("predict", solved, no_q)].score < 1.0
    # the independent student is alike nobody; the blank release's stubs are not answers
    assert not [p for p in report.pairs if "independent" in (p.student_a, p.student_b)]
    assert not [p for p in report.pairs if submissions.BLANK in (p.student_a, p.student_b)]
    # whatever cannot be compared is said
    assert any("truncated" in line and "not a readable notebook" in line for line in report.not_compared)
    assert any("broken" in line and "predict is not valid Python" in line for line in report.not_compared)


def test_command_prints_and_writes_the_report_and_changes_nothing(class_dir, capsys):
    before = {p: p.read_bytes() for p in class_dir.rglob("*") if p.is_file()}
    out = class_dir.parent / "similarity.csv"
    assert main(["similarity", str(class_dir), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "train-kf / kupdate" in printed
    assert "identical (4 students, the model answer): broken, disguised, solved, train-kf_predict_no-Q" in printed
    header, *rows = out.read_text().splitlines()
    assert header == "lab,blank,student_a,student_b,score,tokens,model_answer"
    assert "train-kf,kupdate,disguised,solved,1,52,yes" in rows
    assert {p: p.read_bytes() for p in class_dir.rglob("*") if p.is_file()} == before


def test_answers_too_large_or_too_deep_to_parse_are_listed_and_the_rest_compared(tmp_path):
    """A hostile answer cannot make the report take the instructor's memory or time (before: a
    1 MB list literal was parsed, a tree of hundreds of MB, and compared token by token; a sum of
    1,000 terms, nested deeper than unparsing follows, raised RecursionError out of the report)."""
    import time

    huge = "def predict(x, B, A, Q):\n    return [" + "1, " * 400_000 + "]\n"
    deep = "def kupdate(x_f, B_f, y, H, R):\n    return 1" + " + 1" * 1_000 + "\n"
    for student, nb in {"huge": with_answers({"predict": huge, "kupdate": deep}),
                        submissions.SOLVED: submissions.solved(LAB), "copy": submissions.solved(LAB)}.items():
        path = tmp_path / student / LAB.id / LAB.notebook_name
        path.parent.mkdir(parents=True)
        nbformat.write(nb, path)
    start = time.monotonic()
    report = similarity.compare(tmp_path, [LAB])
    assert time.monotonic() - start < 60
    assert any("huge" in line and "predict holds" in line and "more than the report compares" in line
               for line in report.not_compared)
    assert any("huge" in line and "kupdate is not valid Python, or is nested deeper" in line for line in report.not_compared)
    assert ("predict", ("copy", submissions.SOLVED)) in {(g.blank, g.students) for g in report.groups}


def test_a_copy_padded_with_comments_is_still_compared(tmp_path):
    """An adversarial review padded a copied answer with 30,000 characters of comments: under a cap on
    characters it was never compared, only listed as too long. Comments do not count now."""
    padded = MODEL["kupdate"] + "".join(f"# {'x' * 70}\n" for _ in range(400))
    for student, nb in {"author": submissions.solved(LAB), "copier": with_answers({"kupdate": padded})}.items():
        path = tmp_path / student / LAB.id / LAB.notebook_name
        path.parent.mkdir(parents=True)
        nbformat.write(nb, path)
    report = similarity.compare(tmp_path, [LAB])
    assert ("kupdate", "author", "copier") in {(p.blank, p.student_a, p.student_b) for p in report.pairs}
    assert report.not_compared == []

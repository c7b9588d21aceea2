"""Taking a class's submissions into the course folder: ``SUBMISSIONS/<student>/<lab>/<lab>.ipynb``
becomes nbgrader's ``submitted/<student>/<lab>/``, each file read defensively. When ``SUBMISSIONS`` is
the course's own ``submitted/`` (nbgrader's ``collect`` on a hub), it is left as collected, and the
copies that autograde reads go into ``intake/<student>/<lab>/`` instead (``graded_from``)."""

from __future__ import annotations

import os
import re
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path

import nbformat
from nbgrader.utils import parse_utc
from nbformat import NotebookNode

from autograder import cells
from autograder.labs import Lab
from autograder.pipeline.restore import add_grader_notes, forget_grader_notes

MAX_SUBMISSION_BYTES = 50_000_000
"""The largest notebook file the grader reads (a lab's solved notebook, figures and all, is under 2 MB):
a larger one is graded as empty, since reading it could take the grader's memory."""
STUDENT_ID = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*")
"""Our student ids are folder names: letters, digits, ``_``, ``.`` and ``-``, beginning with a letter or a digit."""
SUBMITTED = "submitted"
"""nbgrader's folder of submissions in a course folder, where its ``collect`` and ``zip_collect`` put them."""
EXCHANGE_INTAKE = "intake"
"""Where ``grade`` writes the copies it autogrades when ``SUBMISSIONS`` is the course's own ``submitted/``."""
SECRET = "submission_secret.txt"
"""The file that nbgrader's ``submit`` writes beside the notebook and ``collect`` copies into ``submitted/``:
``release_feedback`` names the student's feedback by it, so it must reach ``feedback/<student>/<lab>/``."""
MAX_SECRET_BYTES = 4096
"""The most of a ``submission_secret.txt`` copied (nbgrader's holds 128 characters)."""

def read_submission(folder: Path, lab: Lab) -> tuple[NotebookNode, list[str]]:
    """The notebook in a student's ``folder`` for ``lab``, and notes on anything wrong with it.

    A notebook under another name is taken if it is the only one. A file that is not a readable
    notebook (not JSON, truncated, invalid) is replaced by the blank release notebook, so that it
    is graded as an empty submission, with the reason in its notes. So is a notebook reached through
    a symbolic link (the notebook, its folder or the student's folder): the grader would read
    whatever file it points to, another student's notebook or the course's solved source. So is a
    file larger than MAX_SUBMISSION_BYTES. A grader's note that arrives inside the file becomes an
    ordinary cell of the student's: only the grader writes notes.
    """
    linked = [p for p in (folder.parent, folder, *folder.glob("*.ipynb")) if p.is_symlink()]
    if linked:
        return cells.read(lab.release_notebook), [
            f"{linked[0].name} is a symbolic link to {linked[0].readlink()}, not the student's own file; "
            "it was graded as an empty submission."
        ]
    expected = folder / lab.notebook_name
    found = sorted(folder.glob("*.ipynb"))
    if expected.exists():
        path, notes = expected, []
    elif len(found) == 1:
        path, notes = found[0], [f"It was submitted as {found[0].name} and graded as {lab.notebook_name}."]
    else:
        listed = ", ".join(p.name for p in found) or "none"
        return cells.read(lab.release_notebook), [
            f"No notebook named {lab.notebook_name} was found (notebooks there: {listed}); "
            "it was graded as an empty submission."
        ]
    size = path.stat().st_size
    if size > MAX_SUBMISSION_BYTES:
        return cells.read(lab.release_notebook), notes + [
            f"{path.name} is {size:,} bytes, more than the {MAX_SUBMISSION_BYTES:,} the grader reads; "
            "it was graded as an empty submission."
        ]
    try:
        nb = nbformat.read(path, as_version=4)
        nbformat.validate(nb)
    except Exception as error:  # not JSON, truncated, not a notebook: any of nbformat's errors
        reason = " ".join(str(error).split())[:160] or type(error).__name__
        return cells.read(lab.release_notebook), notes + [
            f"{path.name} could not be read as a notebook ({type(error).__name__}: {reason}); "
            "it was graded as an empty submission."
        ]
    forget_grader_notes(nb)
    return nb, notes


def class_list(submissions: Path, labs: list[Lab]) -> dict[str, list[str]]:
    """Lab id -> the students with a folder ``submissions/<student>/<lab>/``, for these labs; a
    folder not named by a student id is left out (``not_student_ids``)."""
    return {lab.id: sorted(p.parent.name for p in submissions.glob(f"*/{lab.id}")
                           if p.is_dir() and STUDENT_ID.fullmatch(p.parent.name)) for lab in labs}


def not_student_ids(submissions: Path, labs: list[Lab]) -> list[str]:
    """A line for each folder of ``submissions`` with one of these labs in it whose name is not a
    student id (``=2+5``, a formula to a spreadsheet): it is not graded. The path is quoted as Python
    writes it, so that a control character in the name shows rather than acts on the terminal."""
    names = {p.parent.name for lab in labs for p in submissions.glob(f"*/{lab.id}")
             if p.is_dir() and not STUDENT_ID.fullmatch(p.parent.name)}
    return [f"The folder {str(submissions / name)!r} is not named by a student id (letters, digits, _ . -, "
            "beginning with a letter or a digit); it was not graded." for name in sorted(names)]


def graded_from(submissions: Path, workdir: Path) -> str:
    """The folder of ``workdir`` that autograde reads the submissions from: ``submitted/``, or
    ``intake/`` when ``submissions`` is (or is inside) ``workdir/submitted/``, whose collected files
    ``grade`` must not rewrite (nbgrader's ``release_feedback`` needs them as ``collect`` left them)."""
    return EXCHANGE_INTAKE if submissions.resolve().is_relative_to((workdir / SUBMITTED).resolve()) else SUBMITTED


def import_submissions(submissions: Path, workdir: Path, labs: list[Lab],
                       takes: Callable[[str], bool] | None = None) -> dict[str, list[str]]:
    """Put ``submissions/<student>/<lab>/<lab>.ipynb`` into the folder of ``workdir`` that autograde
    reads (``graded_from``: ``submitted/``, or ``intake/`` for the course's own ``submitted/``), for
    these labs (only the students that ``takes`` accepts, when it is given: a shard's).

    Each file goes through ``read_submission``; its notes become a grader's note at the top of the
    notebook, which the feedback shows. A ``timestamp.txt`` beside the notebook (nbgrader's
    submission time) is copied too, so that late penalties apply, and so is a ``submission_secret.txt``
    (nbgrader's), so that ``release_feedback`` finds it beside the feedback. Anything else in the target
    folder goes, but a ``submission_secret.txt`` that nbgrader's ``collect`` put there stays. Each file
    is replaced whole (written beside it, then renamed), so that another process taking in or grading
    the same submission at the same time (overlapping shards in one course folder) always reads a whole
    file, the same. Returns lab id -> students.
    """
    into = workdir / graded_from(submissions, workdir)
    by_lab: dict[str, list[str]] = {}
    for lab in labs:
        by_lab[lab.id] = [s for s in class_list(submissions, [lab])[lab.id] if takes is None or takes(s)]
        for student in by_lab[lab.id]:
            folder = submissions / student / lab.id
            nb, notes = read_submission(folder, lab)
            nb, replaced = _valid_unicode(nb)
            if replaced:
                notes.append(f"It held {replaced} character(s) that are not valid Unicode (lone UTF-16 surrogates), "
                             "which no file can store; each was replaced by \ufffd.")
            stamp = _submission_time(folder / "timestamp.txt")
            if isinstance(stamp, str):
                notes.append(stamp)
            add_grader_notes(nb, notes)
            target = into / student / lab.id
            target.mkdir(parents=True, exist_ok=True)
            files = {lab.notebook_name: (nbformat.writes(nb).rstrip("\n") + "\n").encode()}  # as nbformat.write
            if isinstance(stamp, bytes):
                files["timestamp.txt"] = stamp
            secret = _submission_secret(folder)
            if secret is not None:
                files[SECRET] = secret
            for stale in target.iterdir():
                if stale.name in files or stale.name.startswith(PARTIAL) or stale.name == SECRET:
                    continue
                if stale.is_dir() and not stale.is_symlink():
                    shutil.rmtree(stale, ignore_errors=True)
                else:
                    stale.unlink(missing_ok=True)
            for name, data in files.items():
                _replace(target / name, data)
    return by_lab


def _valid_unicode(nb: NotebookNode) -> tuple[NotebookNode, int]:
    """The notebook with every lone UTF-16 surrogate in its text replaced by U+FFFD, and how many there were.
    JSON allows them, but nothing can write them as UTF-8: one in a cell stopped ``grade`` for the whole class
    (adversarial review of issue 31)."""
    text = nbformat.writes(nb)
    count = sum(1 for ch in text if "\ud800" <= ch <= "\udfff")
    if not count:
        return nb, 0
    return nbformat.reads("".join("\ufffd" if "\ud800" <= ch <= "\udfff" else ch for ch in text), as_version=4), count


def _submission_time(path: Path) -> bytes | str | None:
    """The ``timestamp.txt`` to copy (bytes), or a note on why it is left out (str), or None if there is none.

    One that nbgrader cannot read as a time made the whole submission "not graded" (adversarial review):
    it is left out, so the submission is graded with no late penalty, and the note tells the instructor."""
    if not path.exists() or path.is_symlink():
        return None
    data = path.read_bytes()[:200]
    try:
        parse_utc(data.decode().strip())
    except (ValueError, OverflowError, UnicodeDecodeError, TypeError):
        return ("Its timestamp.txt does not hold a time, so it was left out: no late penalty was computed. "
                "Check when it was submitted.")
    return data


def _submission_secret(folder: Path) -> bytes | None:
    """The ``submission_secret.txt`` in a student's ``folder`` to copy, or None if there is none or it is
    reached through a symbolic link (it would name the feedback of whichever submission it points to)."""
    path = folder / SECRET
    if any(p.is_symlink() for p in (folder.parent, folder, path)) or not path.is_file():
        return None
    with open(path, "rb") as handle:
        return handle.read(MAX_SECRET_BYTES)


PARTIAL = ".partial-"
"""How the name of a file being written into ``submitted/`` (or ``intake/``) begins, before it is renamed into place."""


def _replace(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` whole: into a file of its own beside it (readable by all, as a file
    that Python creates is by default), then renamed over it."""
    with tempfile.NamedTemporaryFile(dir=path.parent, prefix=f"{PARTIAL}{path.name}.", delete=False) as handle:
        handle.write(data)
    os.chmod(handle.name, 0o644)
    os.replace(handle.name, path)

"""Taking a class's submissions into the course folder: ``SUBMISSIONS/<student>/<lab>/<lab>.ipynb``
becomes nbgrader's ``submitted/<student>/<lab>/``, each file read defensively. When ``SUBMISSIONS`` is
the course's own ``submitted/`` (nbgrader's ``collect`` on a hub), it is left as collected, and the
copies that autograde reads go into ``intake/<student>/<lab>/`` instead (``graded_from``)."""

from __future__ import annotations

import os
import re
import secrets
import shutil
import stat
import tempfile
from collections.abc import Callable
from datetime import datetime, timezone
from pathlib import Path

import nbformat
from nbgrader.utils import parse_utc
from nbformat import NotebookNode

from autograder import cells
from autograder.kernel.wire import replace_lone_surrogates
from autograder.labs import DUE_DATES, Lab
from autograder.pipeline.late import read_due_dates
from autograder.pipeline.restore import add_grader_notes, forget_grader_notes

MAX_SUBMISSION_BYTES = 50_000_000
"""The largest notebook file the grader reads (a lab's solved notebook, figures and all, is under 2 MB):
a larger one is graded as empty, since reading it could take the grader's memory."""
STUDENT_ID = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.@-]*")
"""Our student ids are folder names: letters, digits, ``_``, ``.``, ``@`` and ``-``, beginning with a letter or a
digit (so that no id is a formula to a spreadsheet; ``@`` for a hub's e-mail-like usernames)."""
SUBMITTED = "submitted"
"""nbgrader's folder of submissions in a course folder, where its ``collect`` and ``zip_collect`` put them."""
EXCHANGE_INTAKE = "intake"
"""Where ``grade`` writes the copies it autogrades when ``SUBMISSIONS`` is the course's own ``submitted/``."""
SECRET = "submission_secret.txt"
"""The file that nbgrader's ``submit`` writes beside the notebook and ``collect`` copies into ``submitted/``:
``release_feedback`` names the student's feedback by it, so it must reach ``feedback/<student>/<lab>/``."""
NBGRADER_SECRET = re.compile(rb"[0-9a-f]{128}")
"""A ``submission_secret.txt`` as nbgrader's ``submit`` writes it: ``secrets.token_hex(64)``, no newline."""
MAX_TIMESTAMP_BYTES = 200
"""The most of a ``timestamp.txt`` read (nbgrader's is about 30 bytes)."""
TIMESTAMP_FORMAT = "%Y-%m-%d %H:%M:%S.%f %Z"
"""nbgrader's ``Exchange.timestamp_format``, in which a stand-in ``timestamp.txt`` is written (in UTC)."""

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
    return [f"The folder {str(submissions / name)!r} is not named by a student id (letters, digits, _ . @ -, "
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
    (nbgrader's), so that ``release_feedback`` finds it beside the feedback. One of them that is there but
    unreadable (or, for the course's own ``submitted/``, missing: ``release_feedback`` needs both) is
    replaced by a stand-in (``_stand_in_time``, a fresh secret), with a note. Anything else in the target
    folder goes, but a ``submission_secret.txt`` that nbgrader's ``collect`` put there stays. Each file
    is replaced whole (written beside it, then renamed), so that another process taking in or grading
    the same submission at the same time (overlapping shards in one course folder) always reads a whole
    file, the same. Returns lab id -> students.
    """
    into = workdir / graded_from(submissions, workdir)
    from_exchange = into.name == EXCHANGE_INTAKE
    due = read_due_dates(DUE_DATES)
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
            stamp = _submission_time(folder / "timestamp.txt", from_exchange)
            if stamp == b"":
                stamp, note = _stand_in_time(due.get(lab.id))
                notes.append(note)
            secret = _submission_secret(folder, from_exchange)
            if secret == b"":
                secret = secrets.token_hex(64).encode()
                notes.append("Its submission_secret.txt is not one that nbgrader's submit writes, so the grader gave "
                             "it a new one: the student cannot fetch this page with fetch_feedback; send it to them "
                             f"from feedback/{student}/{lab.id}/.")
            add_grader_notes(nb, notes)
            target = into / student / lab.id
            target.mkdir(parents=True, exist_ok=True)
            files = {lab.notebook_name: (nbformat.writes(nb).rstrip("\n") + "\n").encode()}  # as nbformat.write
            if stamp is not None:
                files["timestamp.txt"] = stamp
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
    valid = replace_lone_surrogates(text)
    if valid == text:
        return nb, 0
    return nbformat.reads(valid, as_version=4), sum(a != b for a, b in zip(text, valid))


def _submission_time(path: Path, required: bool) -> bytes | None:
    """The ``timestamp.txt`` to copy; None if there is none (and it is not ``required``); empty if it is not a
    regular file that nbgrader reads as a time (adversarial review: one that was no time made the submission
    "not graded"; a directory stopped ``grade``; a huge one filled the grader's memory)."""
    if not required and not os.path.lexists(path):
        return None
    data = _read_regular(path, MAX_TIMESTAMP_BYTES)
    try:
        parse_utc(data.decode().strip())
    except (ValueError, OverflowError, UnicodeDecodeError, TypeError):
        return b""
    return data


def _stand_in_time(due: datetime | None) -> tuple[bytes, str]:
    """A ``timestamp.txt`` for a submission whose own is unreadable, in nbgrader's format, and the note that says so:
    the lab's due date ``due`` (so no late penalty), or, with none, the time now (none then either). Without one,
    ``release_feedback`` stopped at that student and released no one's feedback after them."""
    when, what = (due, "the lab's due date") if due else (datetime.now(timezone.utc), "the time it was taken in")
    text = when.astimezone(timezone.utc).strftime(TIMESTAMP_FORMAT)
    return text.encode(), (f"Its timestamp.txt is missing or does not hold a time, so {what}, {text}, stands in "
                           "for it: no late penalty was computed. Check when it was submitted.")


def _submission_secret(folder: Path, required: bool) -> bytes | None:
    """The ``submission_secret.txt`` in a student's ``folder`` to copy; None if there is none (and it is not
    ``required``); empty if it is not a regular file of nbgrader's form (``NBGRADER_SECRET``), or is reached
    through a symbolic link (it would name the feedback of whichever submission it points to). An empty,
    non-UTF-8 or directory secret stopped ``release_feedback`` for the class."""
    path = folder / SECRET
    if not required and not os.path.lexists(path):
        return None
    data = b"" if folder.parent.is_symlink() or folder.is_symlink() else _read_regular(path, 129)
    return data if NBGRADER_SECRET.fullmatch(data) else b""


def _read_regular(path: Path, limit: int) -> bytes:
    """At most ``limit`` bytes of ``path``, or none if it is not a regular file (a symbolic link, a directory,
    a FIFO, missing), checked on the file opened, without following a link or waiting on a FIFO."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    except OSError:
        return b""
    if not stat.S_ISREG(os.fstat(fd).st_mode):
        os.close(fd)
        return b""
    with os.fdopen(fd, "rb") as handle:
        return handle.read(limit)


PARTIAL = ".partial-"
"""How the name of a file being written into ``submitted/`` (or ``intake/``) begins, before it is renamed into place."""


def _replace(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` whole: into a file of its own beside it (readable by all, as a file
    that Python creates is by default), then renamed over it."""
    with tempfile.NamedTemporaryFile(dir=path.parent, prefix=f"{PARTIAL}{path.name}.", delete=False) as handle:
        handle.write(data)
    os.chmod(handle.name, 0o644)
    os.replace(handle.name, path)

"""Grading a submission in the lab's cell order, with the lab's cells that it lost put back.

A student can drag cells around or delete them by accident. nbgrader restores deleted test cells
(at the end of the notebook) but not the set-up cell or a deleted answer cell, and it runs cells in
the order it finds them. ``RestoreLabCells`` rebuilds the submission on the released notebook's
skeleton: every nbgrader cell in the lab's order (the student's version where there is one, the
released one otherwise), and every cell the student added right after the lab cell it followed.
Each lab cell's nbgrader metadata (its grade, solution, task and locked flags, points, checksum) is
put back as released, and keys the release does not have are dropped: nbgrader 0.9.6 fails on the
whole submission when a test cell says ``grade: false``, ``solution: true`` or ``task: true``, when
an answer cell says ``grade: true`` or a written answer ``grade: false``, or when a cell's nbgrader
metadata holds a key its schema lacks (``score``, ``comment``). What it changed goes into a
grader's note at the top, which the student sees in the feedback.
"""

from __future__ import annotations

import copy
import hashlib
import hmac
import json
import re
from enum import StrEnum
from typing import NamedTuple

from nbformat import NotebookNode
from nbformat.v4 import new_markdown_cell
from nbgrader.preprocessors import NbGraderPreprocessor

from autograder import cells
from autograder.kernel.wire import replace_lone_surrogates
from autograder.labs import Lab
from autograder.pipeline import grading_secret

NOTE_TITLE = "**Note from the grader.**"
# The notes themselves, as plain text with their kind, are kept in the note cell's metadata under this key.
# Only a cell carrying it is the grader's note: a student cannot forge one by typing the title, and intake
# drops the key from every submitted cell (``forget_grader_notes``).
NOTES_KEY = "autograder_notes"
NOTES_SIGNATURE_KEY = "autograder_notes_signature"
"""The grader's signature of the notes (``forget_forged_notes``)."""
# CommonMark lets a backslash escape any ASCII punctuation character.
CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f]+")
MARKDOWN_PUNCTUATION = re.compile(r"([!-/:-@\[-`{-~])")


class NoteKind(StrEnum):
    """What a grader's note is about. Readers (the class report, the grades CSV) tell notes apart by
    this, never by their text, which can quote a submission's file name or error."""

    CAUSE = "cause"
    """It explains errors: the earlier cell whose failure the failing test cells below follow from."""
    CHANGE = "change"
    """The grader changed something to grade the submission: a file renamed, cells restored, a cell stopped."""
    FLAG = "flag"
    """An integrity finding for the instructor to review (autograder/integrity/flag.py)."""


HEADINGS = {
    NoteKind.CAUSE: "Why the failing cells below failed:",
    NoteKind.CHANGE: "Your notebook was graded with these changes:",
    NoteKind.FLAG: "For your instructor to review:",
}
"""The heading of each kind's list in the note cell, in the order the lists are shown."""


class GraderNote(NamedTuple):
    kind: NoteKind
    text: str


def is_grader_note(cell: NotebookNode) -> bool:
    """Whether ``cell`` is a grader's note written by ``add_grader_notes``."""
    return cell.cell_type == "markdown" and NOTES_KEY in cell.metadata


def _read(entry) -> GraderNote | None:
    """A stored note, or None for an entry that is no note (the grader writes none such)."""
    if isinstance(entry, str):
        # a notebook graded before notes had kinds (2026-11-27) holds bare texts, and only flags began so
        return GraderNote(NoteKind.FLAG if entry.startswith("Flagged for review:") else NoteKind.CHANGE, entry)
    if isinstance(entry, dict) and entry.get("kind") in set(NoteKind) and isinstance(entry.get("text"), str):
        return GraderNote(NoteKind(entry["kind"]), entry["text"])
    return None


def grader_notes(nb: NotebookNode) -> list[GraderNote]:
    """The notes in a notebook's grader's note (its first cell), if it has one: each kind's in the order
    ``HEADINGS`` shows them, so the cause of the errors leads."""
    if nb.cells and is_grader_note(nb.cells[0]) and isinstance(nb.cells[0].metadata[NOTES_KEY], list):
        notes = [note for note in map(_read, nb.cells[0].metadata[NOTES_KEY]) if note is not None]
        return sorted(notes, key=lambda note: list(HEADINGS).index(note.kind))
    return []


def _signature(stored) -> str:
    """HMAC-SHA256, under the course's grading secret, of a note cell's stored notes."""
    text = json.dumps(stored, sort_keys=True, ensure_ascii=True).encode()
    return hmac.new(grading_secret.secret(), text, hashlib.sha256).hexdigest()


def forget_forged_notes(nb: NotebookNode) -> None:
    """Make a note cell that the grader did not sign an ordinary cell of the student's.

    ``grade``'s intake drops every note that arrives with a submission (``forget_grader_notes``), but plain
    ``nbgrader autograde`` has no intake: there a submission's own note cell, with any kinds it likes, reached
    the graded notebook and the class report (adversarial review of issue 31). The grader signs every note cell
    it writes, so autograding keeps only those."""
    first = nb.cells[0] if nb.cells else None
    for cell in nb.cells[1:]:
        cell.metadata.pop(NOTES_KEY, None)
        cell.metadata.pop(NOTES_SIGNATURE_KEY, None)
    if first is None or NOTES_KEY not in first.metadata:
        return
    try:
        signed = hmac.compare_digest(str(first.metadata.get(NOTES_SIGNATURE_KEY, "")), _signature(first.metadata[NOTES_KEY]))
    except (TypeError, ValueError, RecursionError):
        signed = False
    if not signed:
        first.metadata.pop(NOTES_KEY, None)
        first.metadata.pop(NOTES_SIGNATURE_KEY, None)


def as_markdown(text: str) -> str:
    """``text`` escaped so that Markdown shows it exactly as written."""
    return MARKDOWN_PUNCTUATION.sub(r"\\\1", text)


def forget_grader_notes(nb: NotebookNode) -> None:
    """Make any grader's note in a submitted notebook an ordinary cell of the student's.

    Only the grader writes notes; one that arrives with the submission was made by hand."""
    for cell in nb.cells:
        cell.metadata.pop(NOTES_KEY, None)
        cell.metadata.pop(NOTES_SIGNATURE_KEY, None)


def _one_line(text: str) -> str:
    """A note's text on one line, with what no file can store (a lone surrogate, from a file name that is not
    UTF-8) replaced by U+FFFD and control characters (a newline in a file name) by spaces."""
    return CONTROL.sub(" ", replace_lone_surrogates(text))


def add_grader_notes(nb: NotebookNode, notes: list[str], kind: NoteKind = NoteKind.CHANGE) -> None:
    """Add notes of one kind to the notebook's grader's note, creating it as the first cell if needed.

    The notes are shown as written: code names such as ``__import__`` are not read as Markdown."""
    if not notes:
        return
    existing = grader_notes(nb)
    if existing:
        nb.cells.pop(0)
    every = existing + [GraderNote(kind, _one_line(text)) for text in notes]
    every.sort(key=lambda note: list(HEADINGS).index(note.kind))
    body = [NOTE_TITLE]
    for heading_kind, heading in HEADINGS.items():
        texts = [note.text for note in every if note.kind == heading_kind]
        if texts:
            body += ["", heading, *(f"- {as_markdown(text)}" for text in texts)]
    stored = [{"kind": str(note.kind), "text": note.text} for note in every]
    # an id from the notes, not a random one: the graded notebook is then the same file every time the
    # same submission is graded, and so are its hidden cases (autograder/pipeline/grading_secret.py)
    digest = hashlib.sha256("\n".join(f"{note.kind}:{note.text}" for note in every).encode()).hexdigest()[:12]
    metadata = {NOTES_KEY: stored, NOTES_SIGNATURE_KEY: _signature(stored)}
    nb.cells.insert(0, new_markdown_cell("\n".join(body), metadata=metadata, id="grader-note-" + digest))


def _has_id(cell: NotebookNode) -> bool:
    return "grade_id" in cells.meta(cell)


def _keep_cell_ids_unique(nb: NotebookNode, restored: list[NotebookNode]) -> None:
    """Give the student's cells that share a cell id with a restored lab cell an id of their own.

    (A test cell that lost its nbgrader metadata keeps its id; the copy put back has it too, and
    nbformat would otherwise warn about the duplicate on every later read.)"""
    taken = {c.get("id") for c in restored}
    used = {c.get("id") for c in nb.cells}
    put_back = {id(c) for c in restored}
    for cell in nb.cells:
        if cell.get("id") in taken and id(cell) not in put_back:
            new_id = next(f"{cell.id[:56]}-{k}" for k in range(1, len(used) + 2) if f"{cell.id[:56]}-{k}" not in used)
            used.add(new_id)
            cell.id = new_id


class RestoreLabCells(NbGraderPreprocessor):
    """Reorder a submission to the lab's order and restore missing lab cells (see the module doc)."""

    def preprocess(self, nb: NotebookNode, resources: dict) -> tuple[NotebookNode, dict]:
        lab = Lab(resources["nbgrader"]["assignment"])
        forget_forged_notes(nb)
        released = cells.read(lab.release_notebook)
        order = [cells.grade_id(c) for c in released.cells if _has_id(c)]
        note = [c for c in nb.cells[:1] if is_grader_note(c)]  # intake's, kept at the top
        notes: list[str] = []
        students = [c for c in nb.cells if not is_grader_note(c)]

        for cell in students:
            # A cell that claims a grade_id the lab does not have (or a second copy of one) is the
            # student's own: without this, nbgrader 0.9.6 fails on the whole submission.
            if "nbgrader" in cell.metadata and (not _has_id(cell) or cells.grade_id(cell) not in order):
                del cell.metadata["nbgrader"]
        mine: dict[str, NotebookNode] = {}
        added: dict[str | None, list[NotebookNode]] = {None: []}
        previous = None
        for cell in students:
            if _has_id(cell) and cells.grade_id(cell) in order and cells.grade_id(cell) not in mine:
                previous = cells.grade_id(cell)
                mine[previous] = cell
                added[previous] = []
            else:
                added[previous].append(cell)

        seen = [cells.grade_id(c) for c in students if _has_id(c) and cells.grade_id(c) in order]
        if seen != [i for i in order if i in mine]:
            notes.append("Its cells were not in the lab's order; it was graded in the lab's order.")
        missing = [i for i in order if i not in mine]
        if missing:
            notes.append(f"Cells that were missing were put back as released: {', '.join(missing)}.")

        by_id = {cells.grade_id(c): c for c in released.cells if _has_id(c)}
        retagged = [i for i in order if i in mine and mine[i].metadata["nbgrader"] != by_id[i].metadata["nbgrader"]]
        for i in retagged:
            mine[i].metadata["nbgrader"] = copy.deepcopy(by_id[i].metadata["nbgrader"])
        if retagged:
            notes.append(f"The nbgrader metadata of cells {', '.join(retagged)} was not as released; "
                         "it was graded as released.")
        nb.cells = note + added[None] + [c for i in order for c in [mine.get(i, by_id[i]), *added.get(i, [])]]
        for cell in nb.cells:
            # the rest of a cell's metadata is the student's, and pages obey some of it: transient.remove_source and
            # jupyter.source_hidden took a written answer, its score and the grader's comment off the feedback page
            # and formgrader's (an adversarial review of issue 36)
            for key in [k for k in cell.metadata if k not in (NOTES_KEY, "nbgrader")]:
                del cell.metadata[key]
        _keep_cell_ids_unique(nb, restored=[by_id[i] for i in missing])
        add_grader_notes(nb, notes)
        return nb, resources

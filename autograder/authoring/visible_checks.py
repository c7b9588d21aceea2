"""What a blank's visible checks say of other answers to it: the solved notebook's cells run in this
process (not the graded ones, and none after the last visible check), and before each blank's check
cell, each answer given for that blank, with the check cell run on it; then the model answer again.

Used to measure which catalogued mistakes the visible checks already fail (``python -m autograder
labs``), and by the tests: every correct alternative passes them, the mistakes they were given a
case for fail them, and their messages read as sentences.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import linecache
import traceback
from collections.abc import Iterable, Iterator

from autograder import cells
from autograder.labs import Lab
from course.checks import CHECK_HINT, explain, wrap


class SolvedNotebookFails(AssertionError):
    """A cell of the solved notebook itself failed: the lab is broken, not the answer tried."""


def run_cell(code: str, namespace: dict) -> BaseException | None:
    """Run a cell's code (IPython magics left out) in ``namespace``: the exception it raised, or None.

    The code is registered with linecache under a name of its own, as IPython registers a cell, so that a
    traceback, and the explanation of ``course.checks`` made from it, quotes its lines as a student reads them."""
    source = "\n".join(line for line in code.splitlines() if not line.lstrip().startswith("%"))
    name = f"<cell {hashlib.sha1(source.encode()).hexdigest()[:12]}>"
    linecache.cache[name] = (len(source), None, [line + "\n" for line in source.splitlines()], name)
    try:
        exec(compile(source, name, "exec"), namespace)
    except Exception as error:  # noqa: BLE001 (the failure is what the caller reads)
        return error
    return None


@contextlib.contextmanager
def _in_lab_folder(lab: Lab) -> Iterator[None]:
    """Where a notebook's cells run here: in the lab's folder, printed text dropped, figures drawn on Agg."""
    import matplotlib

    matplotlib.use("Agg")
    with contextlib.chdir(lab.source_notebook.parent), contextlib.redirect_stdout(io.StringIO()):
        yield


def visible_verdicts(lab: Lab, answers: Iterable[tuple[str, str, str]]) -> dict[str, BaseException | None]:
    """For each (key, blank, code) of ``answers``: what the blank's visible checks raised with ``code``
    in place of the model answer (None: they passed). Raises SolvedNotebookFails if a cell fails on
    the solved notebook."""
    import matplotlib.pyplot as plt

    by_blank: dict[str, list[tuple[str, str]]] = {}
    for key, blank, code in answers:
        by_blank.setdefault(blank, []).append((key, code))
    nb = cells.read(lab.source_notebook)
    model = {cells.grade_id(c): c.source for c in nb.cells if cells.is_code_answer(c)}
    code_cells = [c for c in nb.cells if c.cell_type == "code" and not cells.meta(c).get("grade")]
    last_check = max(i for i, c in enumerate(code_cells) if cells.is_visible_check(c))
    namespace: dict = {"__name__": "__main__"}
    verdicts: dict[str, BaseException | None] = {}
    with _in_lab_folder(lab):
        for cell in code_cells[:last_check + 1]:
            gid = cells.meta(cell).get("grade_id", "")
            blank = gid.removeprefix(cells.CHECK_PREFIX)
            for key, code in by_blank.get(blank, []) if cells.is_visible_check(cell) else []:
                verdicts[key] = run_cell(code, namespace) or run_cell(cell.source, namespace)
                if run_cell(model[blank], namespace) is not None:
                    raise SolvedNotebookFails(f"the model answer of {blank} no longer runs")
                plt.close("all")
            error = run_cell(cell.source, namespace)
            plt.close("all")
            if error is not None:
                raise SolvedNotebookFails(f"{gid or cell.id} fails on the solved notebook: {error}")
    return verdicts


def failing_checks(lab: Lab, answers: dict[str, str]) -> set[str]:
    """The blanks whose visible check cells raise when the solved notebook is run with ``answers``
    (blank -> code) in place of the model answers, as one student's notebook: a wrong answer can fail
    the checks of the blanks that use it too."""
    import matplotlib.pyplot as plt

    nb = cells.read(lab.source_notebook)
    namespace: dict = {"__name__": "__main__"}
    failing = set()
    with _in_lab_folder(lab):
        for cell in (c for c in nb.cells if c.cell_type == "code" and not cells.meta(c).get("grade")):
            gid = cells.meta(cell).get("grade_id", "")
            code = answers.get(gid, cells.model_answer(cell)) if cells.is_code_answer(cell) else cell.source
            if run_cell(code, namespace) is not None and cells.is_visible_check(cell):
                failing.add(gid.removeprefix(cells.CHECK_PREFIX))
            plt.close("all")
    return failing


def mistakes_caught(lab: Lab) -> tuple[int, int, int]:
    """(how many of the lab's catalogued mistakes its visible checks fail, for how many of those the message
    names the fix (``names_the_fix``), how many mistakes there are)."""
    from autograder.catalogues.mistakes import catalogue

    model = cells.model_answers(cells.read(lab.source_notebook))
    mistakes = catalogue(lab)
    verdicts = visible_verdicts(lab, [(m.student_id(lab), m.blank, m.apply(model[m.blank])) for m in mistakes])
    failed = [(m, verdicts[m.student_id(lab)]) for m in mistakes if verdicts.get(m.student_id(lab)) is not None]
    return len(failed), sum(names_the_fix(error, list(model)) for _, error in failed), len(mistakes)


def visible_message(error: BaseException, blanks: list[str]) -> str:
    """What a student reads when a check cell raises ``error``: a crash inside one of ``blanks`` (the blank
    checked and those it calls) explained by course.checks.explain, or the check's own message, wrapped."""
    return explain(error, error.__traceback__, blanks) or wrap(f"{type(error).__name__}: {error}")


def names_the_fix(error: BaseException, blanks: list[str]) -> bool:
    """Whether the message of ``error`` says what to do about it, not only what is wrong: a crash's message
    carries the check's hint for that call, and a failed check was given a hint (a check helper without a
    ``hint`` argument, such as check_pair, says what to do in its own words)."""
    if not isinstance(error, AssertionError):
        return CHECK_HINT in visible_message(error, blanks)
    frames = [frame for frame, _ in traceback.walk_tb(error.__traceback__)]
    raising = frames[-1] if frames else None
    if raising is None or raising.f_globals.get("__name__") == "__main__":
        return False  # a bare assert in a cell, or an AssertionError of the student's own
    return bool(raising.f_locals.get("hint", True))


"""Hidden inputs cannot be learned from one submission and used in the next (issue 29 §2).

A two-round harvest, on every lab. Round 1 submits the solved notebook with every blank wrapped so
that, whenever the hidden tests call it, it prints the arguments it was given (as a hash) and what
it returned, into the student's own graded notebook. Round 2 submits a notebook with no code at
all: each blank looks its arguments up in round 1's table and returns what was recorded. With fixed
hidden cases (the kit before autograder/hidden_tests/cases.py) round 2 earned the points of every
blank whose cases do not depend on a random generator it must advance; now each submission draws
its cases from its own seed, so round 2 finds none of its cases in the table and earns nothing.
"""

from __future__ import annotations

import inspect

import nbformat
import pytest

from autograder import cells
from autograder.catalogues import submissions
from autograder.catalogues.cheats import _add_cell_after_setup
from autograder.labs import Lab
from autograder.pipeline import grading
from over_labs import LABS, about, chosen

KEY = '''
def _harvest_key(args, kwargs):
    """A hash of a call's arguments: arrays by dtype, shape and bytes, everything else by repr."""
    import hashlib
    import numpy as np

    def parts(value):
        if isinstance(value, np.random.Generator):
            return ["generator", repr(value.bit_generator.state)]
        if isinstance(value, (np.ndarray, np.number, float, int)) and not isinstance(value, bool):
            array = np.asarray(value)
            return [str(array.dtype), array.shape, array.tobytes().hex()]
        if isinstance(value, (list, tuple)):
            return [type(value).__name__, [parts(item) for item in value]]
        if isinstance(value, dict):
            return ["dict", sorted(value)]  # an info dict is written by the call, not read
        if callable(value):
            return ["callable"]
        return [repr(value)]

    return hashlib.sha256(repr(parts([list(args), sorted(kwargs.items())])).encode()).hexdigest()
'''

RECORD = '''
def _harvested(function):
    import base64
    import pickle

    def recording(*args, **kwargs):
        result = function(*args, **kwargs)
        try:
            print("HARVEST", function.__name__, _harvest_key(args, kwargs), base64.b64encode(pickle.dumps(result)).decode())
        except Exception:
            pass
        return result

    recording.__name__ = function.__name__
    return recording


{name} = _harvested({name})
'''

ANSWER = '''def {name}(*args, **kwargs):
    import base64
    import pickle

    return pickle.loads(base64.b64decode(_HARVEST[("{name}", _harvest_key(args, kwargs))]))
'''


def _round_one(lab: Lab) -> nbformat.NotebookNode:
    nb = submissions.solved(lab)
    for cell in nb.cells:
        if cells.is_code_answer(cell):
            cell.source += "\n\n" + RECORD.format(name=cells.grade_id(cell))
    return _add_cell_after_setup(nb, KEY)


def _table(autograded: nbformat.NotebookNode) -> dict[tuple[str, str], str]:
    """(blank, argument hash) -> the pickled result, from every HARVEST line the notebook shows."""
    table = {}
    for cell in autograded.cells:
        for output in cell.get("outputs", []):
            for line in str(output.get("text", "")).splitlines():
                parts = line.split(" ")
                if parts[0] == "HARVEST" and len(parts) == 4:  # a line the output cap cut is left out
                    table[parts[1], parts[2]] = parts[3]
    return table


def _round_two(lab: Lab, table: dict) -> nbformat.NotebookNode:
    nb = cells.read(lab.release_notebook)
    for cell in nb.cells:
        if cells.is_code_answer(cell):
            cell.source = ANSWER.format(name=cells.grade_id(cell))
    return _add_cell_after_setup(nb, KEY + f"\n\n_HARVEST = {table!r}\n")


@pytest.fixture(scope="module")
def harvest(request, tmp_path_factory):
    """Round 1 and round 2 of every chosen lab, graded: lab id -> (round 1's table, round 2's GradeRow)."""
    labs = chosen(request.config, LABS)
    first, workdir = tmp_path_factory.mktemp("round1"), tmp_path_factory.mktemp("course")
    for lab in labs:
        submissions.write(_round_one(lab), first, "harvester", lab)
    grading.grade(first, workdir, jobs=2)
    tables = {lab.id: _table(cells.read(workdir / "autograded" / "harvester" / lab.id / lab.notebook_name))
              for lab in labs}
    second = tmp_path_factory.mktemp("round2")
    for lab in labs:
        submissions.write(_round_two(lab, tables[lab.id]), second, "replayer", lab)
    rows = {row.lab: row for row in grading.grade(second, workdir, jobs=2).rows if row.student == "replayer"}
    return {lab.id: (tables[lab.id], rows[lab.id]) for lab in labs}


def _constant_blanks(lab: Lab) -> set[str]:
    """The blanks that take no argument: their one right answer is a constant, which a student may
    write down (castaway-bob's observation_matrix), so a table of it is no harvest."""
    reference = lab.reference()
    return {name for name in lab.blanks() if not inspect.signature(getattr(reference, name)).parameters}


@about(*LABS)
def test_answers_harvested_in_one_submission_earn_nothing_in_the_next(harvest):
    for lab_id, (table, row) in harvest.items():
        blanks = {name for name, _ in table}
        assert blanks, f"{lab_id}: round 1 printed nothing (the harvest itself is broken)"
        constant = {f"test_{name}" for name in _constant_blanks(Lab(lab_id))}
        earned = {cell: row.cells[cell] for cell in row.autograded if row.cells[cell] and cell not in constant}
        assert earned == {}, f"{lab_id}: round 2 answered from round 1's table and earned {earned}"

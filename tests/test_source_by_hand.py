"""An instructor runs a source notebook by hand, from the course root, as JupyterLab or
`jupyter nbconvert --execute source/<lab>/<lab>.ipynb` would: the kernel starts in the notebook's
folder, with no PYTHONPATH, and its hidden-test cells import `autograder` (which imports
`solutions`). The instructor's install (`-e .`) makes both importable; the student bundle's
pyproject.toml installs `course` only, and the bundle holds neither package."""

from __future__ import annotations

import copy
import os
import sys
import tomllib

import nbformat
from nbclient import NotebookClient
from nbformat.v4 import new_code_cell

from autograder import cells
from autograder.bundle import student_pyproject, write_bundle
from autograder.labs import ROOT, get_lab
from autograder.leaks import find_leaks

LAB = get_lab("train-kf")


def test_a_source_notebook_runs_top_to_bottom_without_pythonpath():
    nb = copy.deepcopy(cells.read(LAB.source_notebook))
    assert any("import autograder" in c.source or "from autograder" in c.source for c in nb.cells if c.cell_type == "code")
    nb.cells.append(new_code_cell(f"import sys, autograder, solutions\nprint({str(ROOT)!r} in sys.path, autograder.__file__)"))
    env = {name: value for name, value in os.environ.items() if name != "PYTHONPATH"}
    client = NotebookClient(nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(LAB.source_notebook.parent)}})
    client.execute(env=env)  # raises CellExecutionError at the first cell that fails
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs if o.output_type == "error"]
    assert errors == []
    last = "".join(o.get("text", "") for o in nb.cells[-1].outputs)
    assert last.startswith("False "), f"the course root was on the kernel's sys.path: {last}"
    assert str(ROOT / "autograder") in last


def test_the_instructor_installs_the_hidden_packages_and_the_bundle_does_not(tmp_path):
    here = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"]["find"]["include"]
    assert {"course", "autograder", "solutions"} <= set(here)
    student = tomllib.loads(student_pyproject((ROOT / "pyproject.toml").read_text()))["tool"]["setuptools"]["packages"]["find"]["include"]
    assert student == ["course", "course.*"]
    bundle = write_bundle(tmp_path / "bundle")
    assert (bundle / "pyproject.toml").read_text() == student_pyproject((ROOT / "pyproject.toml").read_text())
    assert find_leaks(bundle) == []
    assert sys.executable  # the test runs in the instructor's environment, where both import:
    import autograder
    import solutions

    assert autograder.__file__.startswith(str(ROOT)) and solutions.__file__.startswith(str(ROOT))

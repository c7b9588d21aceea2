"""An instructor runs a source notebook by hand, as README says: from the course root, with the
root on PYTHONPATH (`PYTHONPATH=$PWD jupyter nbconvert --execute ...` or `... jupyter lab`). The
kernel starts in the notebook's folder and its hidden-test cells import `solutions` (whose hidden tests
import `autograder`) through that PYTHONPATH. Without it they cannot: the hidden packages are installed
nowhere (`-e .` installs `course` only, here and in the student bundle), so that no kernel of the
instructor's environment, a grading kernel included, finds the reference by accident."""

from __future__ import annotations

import copy
import os
import sys
import tomllib

from nbclient import NotebookClient
from nbformat.v4 import new_code_cell

from autograder import cells
from autograder.release.bundle import student_pyproject, write_bundle
from autograder.labs import ROOT, get_lab
from autograder.release.leaks import find_leaks
from importable import importable

LAB = get_lab("train-kf")


def test_a_source_notebook_runs_top_to_bottom_with_the_course_root_on_pythonpath():
    nb = copy.deepcopy(cells.read(LAB.source_notebook))
    assert any("from solutions." in c.source for c in nb.cells if c.cell_type == "code")
    nb.cells.append(new_code_cell("import autograder, solutions\nprint(autograder.__file__)"))
    env = {**{name: value for name, value in os.environ.items() if name != "PYTHONPATH"}, "PYTHONPATH": str(ROOT)}
    client = NotebookClient(nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(LAB.source_notebook.parent)}})
    client.execute(env=env)  # raises CellExecutionError at the first cell that fails
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs if o.output_type == "error"]
    assert errors == []
    assert "".join(o.get("text", "") for o in nb.cells[-1].outputs).startswith(str(ROOT / "autograder"))


def test_no_hidden_package_is_installed_here_or_in_the_bundle(tmp_path):
    here = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"]["find"]["include"]
    assert here == ["course", "course.*"]
    bundle = write_bundle(tmp_path / "bundle")
    assert (bundle / "pyproject.toml").read_text() == student_pyproject((ROOT / "pyproject.toml").read_text())
    assert find_leaks(bundle) == []
    # this environment, outside the course root and without PYTHONPATH, as a kernel started elsewhere
    assert importable(sys.executable, tmp_path) == {"solutions": False, "autograder": False, "course": True}

"""Release hygiene: release/ is in sync with source/, and nothing students get leaks the answers."""

import json
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

from autograder import cells
from autograder.release import data, leaks
from autograder.pipeline import versions, nbgrader_apps
from autograder.release.bundle import LeakFound, write_bundle
from autograder.labs import ROOT
from importable import importable
from over_labs import LABS, about, chosen, over_labs


def _normalised(path: Path) -> dict:
    return json.loads(json.dumps(nbformat.read(path, as_version=4)))


@about(*LABS)
def test_release_is_in_sync_with_source(tmp_path, pytestconfig):
    labs = chosen(pytestconfig, LABS)
    nbgrader_apps.generate_release(labs, tmp_path)
    for lab in labs:
        fresh = tmp_path / "release" / lab.id / lab.notebook_name
        assert _normalised(fresh) == _normalised(lab.release_notebook), (
            f"release/{lab.id} is stale: run `python -m autograder release` and commit it"
        )
        shipped, generated = (sorted(p.relative_to(folder) for p in folder.rglob("*") if p.is_file())
                              for folder in (lab.release_notebook.parent, fresh.parent))
        assert shipped == generated, f"release/{lab.id}"
    assert sorted(p.name for p in (ROOT / "release").iterdir()) == [lab.id for lab in LABS], "a release without a lab"


@about(*LABS)
def test_release_has_no_leaks():
    assert leaks.find_leaks(ROOT / "release") == []


@over_labs
def test_release_keeps_every_blank_as_a_stub_and_every_test_cell(lab):
    release = cells.read(lab.release_notebook)
    for cell in release.cells:
        if cells.is_code_answer(cell):
            assert 'raise NotImplementedError("Not written yet' in cell.source, cells.grade_id(cell)
        if cells.is_autograded_test(cell):
            assert "check_" not in cell.source, f"{cells.grade_id(cell)} still shows its hidden tests"
    written = [c for c in release.cells if cells.is_answer(c) and c.cell_type == "markdown"]
    assert all(c.source == "YOUR ANSWER HERE" for c in written), "model answers and rubrics are stripped"


@over_labs
def test_the_release_run_before_writing_anything_stops_only_where_a_blank_is_needed(lab, tmp_path):
    """A student who runs every cell of the fresh release sees each failing cell name the blanks it
    needs (``require``); no cell fails any other way, and nothing writes to stderr."""
    folder = tmp_path / lab.id
    folder.mkdir()
    nb = cells.read(lab.release_notebook)
    NotebookClient(nb, timeout=120, allow_errors=True, resources={"metadata": {"path": str(folder)}}).execute()
    failed = {}
    for cell in nb.cells:
        for output in cell.get("outputs", []):
            if output.output_type == "error" or (output.output_type == "stream" and output.name == "stderr"):
                failed[cells.grade_id(cell) if "grade_id" in cells.meta(cell) else cell.id] = output.get("ename", "stderr")
    assert failed, "the fresh release should stop at the blanks"
    assert set(failed.values()) == {"NotWrittenYet"}, {c: e for c, e in failed.items() if e != "NotWrittenYet"}


def test_student_bundle_has_no_leaks_and_installs_nothing_hidden(tmp_path):
    bundle = write_bundle(tmp_path / "bundle")
    assert sorted(p.name for p in bundle.iterdir()) == sorted(
        ["release", "course", "requirements.txt", "pyproject.toml", "LICENSE", "README.md", "jupyter_config"]
    )
    assert leaks.find_leaks(bundle) == []
    assert not (bundle / "solutions").exists() and not (bundle / "autograder").exists()


def test_bundle_refuses_a_tree_with_a_leak(tmp_path, monkeypatch):
    planted = tmp_path / "course_with_answer"
    planted.mkdir()
    (planted / "helpers.py").write_text("from solutions.train_kf.reference import predict\n")
    with pytest.raises(LeakFound, match="an import of the reference"):
        from autograder.release.bundle import raise_on_leaks

        raise_on_leaks(planted)


REFERENCE_PREDICT = '''
def forecast(x, B, A, Q):
    """Renamed, with a new docstring: still the reference's body."""
    # x^f_{t+1} = A x_t
    x_f = A @ x
    # B_{t+1} = A B_t A^T + Q
    B_f = A @ B @ A.T + Q
    return x_f, B_f
'''


@pytest.mark.parametrize(
    "text, what",
    [
        (REFERENCE_PREDICT, "has the body of solutions/train_kf/reference.py:predict"),
        ("x = 1\n### BEGIN SOLUTION\n", "a solution delimiter"),
        ("### BEGIN HIDDEN TESTS\n", "a hidden-test delimiter"),
        ("import solutions\n", "an import of the reference"),
        ("   from solutions.train_kf.hidden_tests import check_predict\n", "an import of the reference"),
        ("mod = __import__('solutions')\n", "a reference to the hidden packages"),
        ("open('../../solutions/train_kf/reference.py')\n", "a reference to the hidden packages"),
    ],
)
def test_leak_detector_finds_planted_leaks(tmp_path, text, what):
    (tmp_path / "planted.py").write_text(text)
    found = leaks.find_leaks(tmp_path)
    assert any(what in str(leak) for leak in found), found


def test_leak_detector_finds_a_reference_body_in_a_notebook(tmp_path):
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("%xmode Minimal\n" + REFERENCE_PREDICT)])
    nbformat.write(nb, tmp_path / "lab.ipynb")
    assert [str(leak) for leak in leaks.find_leaks(tmp_path)] == [
        "lab.ipynb: function forecast has the body of solutions/train_kf/reference.py:predict"
    ]


def test_a_function_of_a_drafts_visible_checks_is_no_leak(tmp_path, monkeypatch):
    """A draft is the notebook as text: a helper that its check cell defines is in the release by design,
    and is not reported; a reference's body in the same notebook still is."""
    helper = ("def scripted(x):\n    y = x + 1\n    z = y * 2\n    w = z - 3\n    return [y, z, w, x, y + z]\n")
    root = tmp_path / "root"
    (root / "solutions" / "lab").mkdir(parents=True)
    (root / "solutions" / "lab" / "draft.py").write_text(f"# %%\n{helper}\n# %%\n{REFERENCE_PREDICT}")
    (root / "solutions" / "lab" / "reference.py").write_text(REFERENCE_PREDICT.replace("forecast", "predict"))
    monkeypatch.setattr(leaks, "ROOT", root)
    release = tmp_path / "release"
    release.mkdir()
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(helper), nbformat.v4.new_code_cell(REFERENCE_PREDICT)])
    nbformat.write(nb, release / "lab.ipynb")
    assert [str(leak) for leak in leaks.find_leaks(release)] == [
        "lab.ipynb: function forecast has the body of solutions/lab/reference.py:predict"]


@about(*LABS)
def test_course_implements_no_blank():
    assert leaks.blanks_in_course() == []


def test_student_environment_cannot_import_the_hidden_packages(tmp_path):
    """The student bundle installed as students install it (its `-e .`, in a fresh environment),
    probed outside the bundle without the grader's PYTHONPATH: `course` imports, the hidden
    packages do not (nor in the instructor's environment: tests/test_source_by_hand.py)."""
    bundle = write_bundle(tmp_path / "bundle")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    python = venv / "bin" / "python"
    subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install", "-q", "--no-deps", "-e", str(bundle)],
                   env=env, check=True, capture_output=True)
    assert importable(python, tmp_path) == {"solutions": False, "autograder": False, "course": True}


@about(*LABS)
def test_every_shipped_data_file_is_loaded_by_the_course():
    # Each lab rebuilds its own files in its reference tests (test_<lab>_reference.py, so that the
    # slow builds run on different workers); here, no file ships that no course module loads.
    sources = "\n".join(path.read_text() for path in (ROOT / "course").glob("*.py"))
    unused = [path.name for path in data.DATA_DIR.iterdir() if path.name not in sources]
    assert unused == []


def test_student_bundle_installs_only_what_the_labs_need_and_hides_the_instructor_tools(tmp_path):
    """The bundle's requirements.txt, pyproject.toml and Jupyter configuration (jupyter_config/), as
    a student's JupyterLab reads them: Validate on, formgrader and the exchange-based lists off."""
    bundle = write_bundle(tmp_path / "bundle")
    requirements = (bundle / "requirements.txt").read_text()
    names = {requirement.name for requirement in versions.requirements(bundle / "requirements.txt")}
    assert names == {"numpy", "scipy", "matplotlib", "jupyterlab", "ipykernel", "nbgrader"}, names
    assert "-e ." in requirements.splitlines()
    pyproject = tomllib.loads((bundle / "pyproject.toml").read_text())
    assert "pytest" not in pyproject.get("tool", {}) and pyproject["project"]["name"] == "estimation-lab-kit"
    for path in (bundle / "course").rglob("*.py"):
        assert "python -m autograder" not in path.read_text(), path
    env = {**os.environ, "JUPYTER_CONFIG_DIR": str(bundle / "jupyter_config")}
    probe = (
        "from jupyter_server.serverapp import ServerApp\n"
        "app = ServerApp()\n"
        "app.initialize(argv=['--ServerApp.port=0', '--ServerApp.open_browser=False'])\n"
        "import json\n"
        "print(json.dumps({n: e.enabled for n, e in app.extension_manager.extensions.items() if 'nbgrader' in n}))\n"
    )
    run = subprocess.run([sys.executable, "-c", probe], cwd=bundle, env=env, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    enabled = json.loads(run.stdout.strip().splitlines()[-1])
    assert enabled == {
        "nbgrader.server_extensions.formgrader": False,
        "nbgrader.server_extensions.assignment_list": False,
        "nbgrader.server_extensions.course_list": False,
        "nbgrader.server_extensions.validate_assignment": True,
    }, enabled
    listed = subprocess.run([sys.executable, "-m", "jupyter", "labextension", "list"], cwd=bundle, env=env,
                            capture_output=True, text=True, timeout=300)
    disabled = listed.stdout + listed.stderr
    disabled = disabled[disabled.index("Disabled extensions:"):].split()
    for plugin in ("formgrader", "create-assignment", "assignment-list", "course-list", "menu"):
        assert f"@jupyter/nbgrader:{plugin}" in disabled, disabled
    assert "@jupyter/nbgrader:validate-assignment" not in disabled

"""The student bundle: the solution-free tree that students get, checked for leaks.

Students install only what the labs need (``requirements.txt``, the student lines of the
instructors' ``environment.txt``), get a ``pyproject.toml`` without the instructors' tool
settings, and start JupyterLab with the bundle's own Jupyter configuration (``jupyter_config/``),
which keeps nbgrader's Validate and turns off its instructor tools: formgrader, Create Assignment,
and the assignment and course lists, which need an exchange directory that students do not have.
On a JupyterHub with nbgrader's exchange (deploy/jupyterhub/), students get the same configuration with
the Assignment List (and nbgrader's menu, which opens it) kept on.
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

from autograder.labs import ROOT
from autograder.release.leaks import find_leaks

STUDENT_README = ROOT / "docs" / "student-readme.md"
COPIED = ("release", "course", "LICENSE")

STUDENT_PACKAGES = ("numpy", "scipy", "matplotlib", "jupyterlab", "ipykernel", "nbgrader")
"""What the labs need: the numerics, JupyterLab, and nbgrader for its Validate button."""

REQUIREMENTS = "requirements.txt"
JUPYTER_CONFIG = "jupyter_config"
"""The bundle's Jupyter configuration directory: start JupyterLab with JUPYTER_CONFIG_DIR set to it."""

INSTRUCTOR_LAB_PLUGINS = (
    "@jupyter/nbgrader:formgrader",
    "@jupyter/nbgrader:create-assignment",
    "@jupyter/nbgrader:assignment-list",
    "@jupyter/nbgrader:course-list",
    "@jupyter/nbgrader:menu",
)
INSTRUCTOR_SERVER_EXTENSIONS = (
    "nbgrader.server_extensions.formgrader",
    "nbgrader.server_extensions.assignment_list",
    "nbgrader.server_extensions.course_list",
)
VALIDATE_SERVER_EXTENSION = "nbgrader.server_extensions.validate_assignment"
EXCHANGE_LAB_PLUGINS = ("@jupyter/nbgrader:assignment-list", "@jupyter/nbgrader:menu")
EXCHANGE_SERVER_EXTENSIONS = ("nbgrader.server_extensions.assignment_list",)
"""What students use on a hub with nbgrader's exchange: the Assignment List (fetch, submit, fetch feedback)."""


VALIDATE_CONFIG = """\
# Validate lists the code blanks that fail first, then the written answers, each empty one by its question
# (course/validate_order.py). nbgrader reads this file when the Validate button or `nbgrader validate` runs.
from course.validate_order import list_blanks_first

list_blanks_first()
"""
"""The bundle's nbgrader configuration: Validate's order."""


class LeakFound(RuntimeError):
    """Something that students must not see is in a tree meant for them."""


def student_requirements(environment: str) -> str:
    """The lines of ``environment.txt`` that students need, with the same version ranges."""
    wanted = {}  # package name -> its line
    for line in environment.splitlines():
        name = re.match(r"[A-Za-z0-9_.\-]+", line.strip())
        if name and name.group(0).lower() in STUDENT_PACKAGES:
            wanted[name.group(0).lower()] = line.strip()
    missing = set(STUDENT_PACKAGES) - wanted.keys()
    if missing:
        raise ValueError(f"environment.txt has no line for {', '.join(sorted(missing))}, which students need.")
    return (
        "# What the labs need (the student lines of the instructors' environment.txt, same versions):\n"
        "#   python3 -m venv .venv && .venv/bin/pip install -r requirements.txt     (Python 3.11, from this folder)\n"
        + "\n".join(wanted.values())
        + "\n# the labs' support package `course` (this folder's pyproject.toml)\n-e .\n"
    )


def student_pyproject(pyproject: str) -> str:
    """The course's pyproject.toml without the instructors' tool settings (pytest runs tests/ and source/)."""
    return re.sub(r"\n\[tool\.pytest\.ini_options\]\n.*?(?=\n\[(?!\[)|\Z)", "\n", pyproject, flags=re.DOTALL).rstrip() + "\n"


def write_jupyter_config(folder: Path, exchange: bool = False) -> None:
    """Jupyter configuration that keeps Validate, lists what it finds in the order to fix it, and turns the
    instructor tools off; with ``exchange`` (a hub with nbgrader's exchange), the Assignment List stays on."""
    kept = EXCHANGE_LAB_PLUGINS if exchange else ()
    (folder / "labconfig").mkdir(parents=True)
    (folder / "labconfig" / "page_config.json").write_text(json.dumps(
        {"disabledExtensions": {plugin: True for plugin in INSTRUCTOR_LAB_PLUGINS if plugin not in kept}}, indent=2) + "\n"
    )
    extensions = ({name: False for name in INSTRUCTOR_SERVER_EXTENSIONS} | {VALIDATE_SERVER_EXTENSION: True}
                  | {name: True for name in EXCHANGE_SERVER_EXTENSIONS if exchange})
    (folder / "jupyter_server_config.json").write_text(
        json.dumps({"ServerApp": {"jpserver_extensions": extensions}}, indent=2) + "\n"
    )
    (folder / "nbgrader_config.py").write_text(VALIDATE_CONFIG)


def write_bundle(out: Path) -> Path:
    """Write the student bundle to ``out`` (which must not exist yet) and check it for leaks."""
    if out.exists():
        raise FileExistsError(f"{out} exists already. Choose a new folder for the bundle.")
    out.mkdir(parents=True)
    for name in COPIED:
        source = ROOT / name
        if source.is_dir():
            shutil.copytree(source, out / name, ignore=shutil.ignore_patterns("__pycache__", "*.egg-info", ".ipynb_checkpoints"))
        else:
            shutil.copy2(source, out / name)
    (out / REQUIREMENTS).write_text(student_requirements((ROOT / "environment.txt").read_text()))
    (out / "pyproject.toml").write_text(student_pyproject((ROOT / "pyproject.toml").read_text()))
    write_jupyter_config(out / JUPYTER_CONFIG)
    shutil.copy2(STUDENT_README, out / "README.md")
    raise_on_leaks(out)
    return out


def raise_on_leaks(tree: Path) -> None:
    leaks = find_leaks(tree)
    if leaks:
        raise LeakFound(f"{tree} must not be given to students. It leaks:\n" + "\n".join(f"  {leak}" for leak in leaks))

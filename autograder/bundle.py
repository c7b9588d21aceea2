"""The student bundle: the solution-free tree that students get, checked for leaks."""

from __future__ import annotations

import shutil
from pathlib import Path

from autograder.labs import ROOT
from autograder.leaks import find_leaks

STUDENT_README = ROOT / "docs" / "student-readme.md"
COPIED = ("release", "course", "environment.txt", "LICENSE")
INSTRUCTOR_PACKAGES = (
    "# Here, in the instructor's environment (`-e .` in environment.txt), the hidden packages are installed\n"
    "# beside the student-facing package `course`, so that the source notebooks run by hand. The student\n"
    "# bundle's copy of this file installs `course` only, and the bundle holds nothing else.\n"
    'include = ["course", "course.*", "autograder", "autograder.*", "solutions", "solutions.*"]\n'
)
"""What pyproject.toml installs in the course root (the instructor's environment)."""
STUDENT_PACKAGES = '# The student-facing package `course`.\ninclude = ["course", "course.*"]\n'
"""What the student bundle's pyproject.toml installs instead."""


class LeakFound(RuntimeError):
    """Something that students must not see is in a tree meant for them."""


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
    shutil.copy2(STUDENT_README, out / "README.md")
    (out / "pyproject.toml").write_text(student_pyproject())
    raise_on_leaks(out)
    return out


def student_pyproject() -> str:
    """The course root's pyproject.toml with the packages that students install: ``course`` only."""
    text = (ROOT / "pyproject.toml").read_text()
    if text.count(INSTRUCTOR_PACKAGES) != 1:
        raise ValueError("pyproject.toml no longer lists its packages as autograder/bundle.py expects: update INSTRUCTOR_PACKAGES.")
    return text.replace(INSTRUCTOR_PACKAGES, STUDENT_PACKAGES)


def raise_on_leaks(tree: Path) -> None:
    leaks = find_leaks(tree)
    if leaks:
        raise LeakFound(f"{tree} must not be given to students. It leaks:\n" + "\n".join(f"  {leak}" for leak in leaks))

"""The student bundle: the solution-free tree that students get, checked for leaks."""

from __future__ import annotations

import shutil
from pathlib import Path

from autograder.labs import ROOT
from autograder.leaks import find_leaks

STUDENT_README = ROOT / "docs" / "student-readme.md"
COPIED = ("release", "course", "environment.txt", "pyproject.toml", "LICENSE")


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
    raise_on_leaks(out)
    return out


def raise_on_leaks(tree: Path) -> None:
    leaks = find_leaks(tree)
    if leaks:
        raise LeakFound(f"{tree} must not be given to students. It leaks:\n" + "\n".join(f"  {leak}" for leak in leaks))

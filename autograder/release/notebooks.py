"""Generating the student notebooks in ``release/`` and checking them for leaks."""

from __future__ import annotations

from autograder import private_paths
from autograder.pipeline import nbgrader_apps
from autograder.release.bundle import raise_on_leaks
from autograder.labs import ROOT, Lab, all_labs


def release_all(labs: list[Lab] | None = None) -> None:
    """``nbgrader generate_assignment`` for every lab into ``release/``, then the leak check."""
    nbgrader_apps.generate_release(labs or all_labs())
    raise_on_leaks(ROOT / "release")
    exposed = private_paths.exposed(ROOT)
    if exposed:
        print(private_paths.warning(exposed))

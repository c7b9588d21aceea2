"""Rebuilding the shipped data in ``course/data/`` from each lab's seeded reference build."""

from __future__ import annotations

import filecmp
import tempfile
from pathlib import Path

from autograder.labs import ROOT, Lab, all_labs

DATA_DIR = ROOT / "course" / "data"


def build(lab: Lab, directory: Path) -> list[Path]:
    """Write a lab's data files into ``directory`` with ``solutions.<lab>.write_data``."""
    return lab.solutions().write_data(directory)


def stale_files(labs: list[Lab] | None = None) -> list[str]:
    """Shipped data files that a fresh build does not reproduce byte for byte."""
    stale = []
    with tempfile.TemporaryDirectory() as tmp:
        for lab in labs or all_labs():
            for path in build(lab, Path(tmp)):
                shipped = DATA_DIR / path.name
                if not shipped.exists() or not filecmp.cmp(path, shipped, shallow=False):
                    stale.append(path.name)
    return stale

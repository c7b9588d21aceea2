"""Rebuilding the shipped data in ``course/data/`` (and its records) from each lab's seeded reference build.

Data are optional: a lab ships data if its reference has ``write_data``."""

from __future__ import annotations

import filecmp
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from autograder.labs import ROOT, Lab, all_labs

DATA_DIR = ROOT / "course" / "data"
RECORDS_DIR = ROOT / "solutions" / "records"
"""Records a build writes beside the data (per-run results, solver checkpoints) so that a lab's reference
tests can prove the shipped data equal a rebuild without the whole rebuild; instructors only, never loaded
by ``course``."""
RECORD_SUFFIX = ".records.npz"
"""How a built file's name ends when it is a record (kept in RECORDS_DIR), not data (kept in DATA_DIR)."""


def ships_data(lab: Lab) -> bool:
    """Whether the lab ships data: its reference has ``write_data(directory) -> list[Path]``."""
    return hasattr(lab.reference(), "write_data")


def build(lab: Lab, directory: Path) -> list[Path]:
    """Write a lab's data files (and records) into ``directory`` with ``solutions.<module>.reference.write_data``."""
    return lab.reference().write_data(directory)


def shipped_path(built: Path) -> Path:
    """Where the shipped copy of a built file is kept: RECORDS_DIR for a record, DATA_DIR for data."""
    return (RECORDS_DIR if built.name.endswith(RECORD_SUFFIX) else DATA_DIR) / built.name


@contextmanager
def _fresh_build(labs: list[Lab] | None) -> Iterator[list[Path]]:
    """The files a fresh build of the labs that ship data (of every lab by default) writes into a
    temporary folder, which lasts as long as the ``with`` block."""
    with tempfile.TemporaryDirectory() as tmp:
        yield [path for lab in labs or all_labs() if ships_data(lab) for path in build(lab, Path(tmp))]


def rebuild(labs: list[Lab] | None = None) -> list[Path]:
    """Rebuild the labs' shipped files in place (every lab by default); returns where they were written."""
    written = []
    with _fresh_build(labs) as built:
        for path in built:
            target = shipped_path(path)
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(path, target)
            written.append(target)
    return written


def stale_files(labs: list[Lab] | None = None) -> list[str]:
    """Shipped files (data and records) that a fresh build does not reproduce byte for byte."""
    with _fresh_build(labs) as built:
        return [path.name for path in built
                if not shipped_path(path).exists() or not filecmp.cmp(path, shipped_path(path), shallow=False)]

"""Where each lab's files live. A lab is a folder ``source/<lab>/`` holding ``<lab>.ipynb``."""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parent.parent
"""The course root: the repository, and nbgrader's course directory."""
DUE_DATES = ROOT / "due_dates.toml"
"""Each lab's due date (``autograder/pipeline/late.py`` reads them)."""


@dataclass(frozen=True)
class Lab:
    """One lab, named by its id (``train-kf``); its Python modules use underscores (``train_kf``)."""

    id: str

    @property
    def module(self) -> str:
        return self.id.replace("-", "_")

    @property
    def notebook_name(self) -> str:
        return f"{self.id}.ipynb"

    @property
    def source_notebook(self) -> Path:
        return ROOT / "source" / self.id / self.notebook_name

    @property
    def release_notebook(self) -> Path:
        return ROOT / "release" / self.id / self.notebook_name

    @property
    def hidden_folder(self) -> Path:
        """``solutions/<module>/``: the lab's hidden code, edited together (the reference, its hidden
        tests, the catalogued mistakes, the checks of the lab's claims)."""
        return ROOT / "solutions" / self.module

    @property
    def draft(self) -> Path:
        """``solutions/<module>/draft.py``: the notebook as text, in jupytext's percent format, from which
        ``python -m autograder build`` makes the source notebook (labs made before drafts have none). It
        holds the model answers and hidden tests, so it is kept with the hidden code, never in ``source/``,
        whose other files nbgrader copies into the student release."""
        return self.hidden_folder / "draft.py"

    def hidden_module(self, name: str) -> ModuleType:
        """One module of the lab's hidden code: ``solutions.<module>.<name>`` (``reference``,
        ``hidden_tests``, ``mistakes`` or ``claims``)."""
        return importlib.import_module(f"solutions.{self.module}.{name}")

    def blanks(self) -> tuple[str, ...]:
        """The names of the functions the lab's blanks define, in the notebook's order: read from
        the source notebook, the one list of them."""
        from autograder import cells

        return tuple(cells.blank_names(cells.read(self.source_notebook)))

    def reference(self) -> ModuleType:
        """The lab's reference for every blank, ``solutions.<module>.reference``."""
        return self.hidden_module("reference")


def all_labs() -> list[Lab]:
    """Every lab that has a source notebook, in alphabetical order."""
    return [Lab(p.parent.name) for p in sorted((ROOT / "source").glob("*/*.ipynb")) if p.stem == p.parent.name]


def lab_of(module_name: str) -> Lab:
    """The lab whose hidden code ``module_name`` belongs to (``solutions.<module>.hidden_tests``)."""
    return Lab(module_name.split(".")[1].replace("_", "-"))


def get_lab(lab_id: str) -> Lab:
    """The lab with this id, or a ValueError that lists the labs there are."""
    known = {lab.id: lab for lab in all_labs()}
    if lab_id not in known:
        raise ValueError(f"There is no lab '{lab_id}'. The labs are: {', '.join(known)}.")
    return known[lab_id]

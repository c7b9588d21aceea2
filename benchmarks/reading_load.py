"""How much a student reads in each lab: words and cells of the release notebook, main text and "Going further".

    python benchmarks/reading_load.py [LAB ...]     (default: every lab)

For each lab's release notebook (what students get: no model answers), the script prints the words of
its Markdown before the first heading that starts with "Going further" (the main text) and after it,
the number of cells in each part, the claim markers in each, and the graded blanks and written answers
with their points. Issue 33 asks for a main text that a student reads in about 45 minutes: the kit aims
at about 3,000 words, since a first reading of text with formulas goes at some 60-80 words a minute.
Counts only: nothing is timed, and nothing here is asserted.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import nbformat

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from autograder import cells  # noqa: E402
from autograder.authoring.consistency import GOING_FURTHER  # noqa: E402
from autograder.labs import Lab, all_labs  # noqa: E402

CLAIM = re.compile(r"<!-- claim: ")


def reading_load(lab: Lab) -> dict[str, int]:
    """Counts for one lab's release notebook: words, cells and claim markers of the main text
    (``main_*``) and of its "Going further" part (``further_*``), blanks, written answers and points."""
    nb = nbformat.read(lab.release_notebook, as_version=4)
    counts = dict.fromkeys(("main_words", "main_cells", "main_claims", "further_words", "further_cells",
                            "further_claims", "blanks", "written", "points"), 0)
    part = "main"
    for cell in nb.cells:
        if cell.cell_type == "markdown" and GOING_FURTHER.search(cell.source):
            part = "further"
        counts[f"{part}_cells"] += 1
        if cell.cell_type == "markdown":
            counts[f"{part}_words"] += len(cell.source.split())
            counts[f"{part}_claims"] += len(CLAIM.findall(cell.source))
        if cells.is_code_answer(cell):
            counts["blanks"] += 1
        points = cell.metadata.get("nbgrader", {}).get("points") or 0
        counts["points"] += points
        if points and cell.cell_type == "markdown":
            counts["written"] += 1
    return counts


def main(names: list[str]) -> None:
    """Print a row of counts for each lab named (every lab when none is)."""
    labs = [lab for lab in all_labs() if not names or lab.id in names]
    print(f"{'lab':<18} {'main words':>10} {'cells':>5} {'claims':>6}   {'further words':>13} {'cells':>5} "
          f"{'claims':>6}   {'blanks':>6} {'written':>7} {'points':>6}")
    for lab in labs:
        c = reading_load(lab)
        print(f"{lab.id:<18} {c['main_words']:>10} {c['main_cells']:>5} {c['main_claims']:>6}   "
              f"{c['further_words']:>13} {c['further_cells']:>5} {c['further_claims']:>6}   "
              f"{c['blanks']:>6} {c['written']:>7} {c['points']:>6g}")


if __name__ == "__main__":
    main(sys.argv[1:])

"""How long a student waits for each lab: every solved release notebook run top to bottom, cell by cell.

    python benchmarks/cell_times.py [--repeat 3] [--top 5] [LAB ...]     (default: every lab)

For each lab, the release notebook with every answer filled in with its model answer
(``submissions.solved``) is run in one plain kernel (nbclient, no sandbox, no hidden tests) in a copy
of its folder, ``--repeat`` times. The script prints, per lab, the median of the whole run, the cells
that take longest (median over the runs) and each cell's share of the grading cell limit
(``GRADING_CELL_TIMEOUT``, 30 s by default): a cell over a third of it can pass the limit on a loaded
grading machine, and every graded submission runs the notebook once. Issue 33's goals: a whole run
in 10 s or less on one quiet core, and no cell over a third of the cell limit.

Run it on a quiet machine: the numbers are medians of one run of the script, and only their ratios
compare across machines.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import tempfile
import time
from pathlib import Path

import nbformat
from nbclient import NotebookClient

from autograder import cells
from autograder.catalogues import submissions
from autograder.labs import Lab, all_labs, get_lab

CELL_LIMIT_S = float(os.environ.get("GRADING_CELL_TIMEOUT", "30"))


def cell_seconds(lab: Lab) -> dict[str, float]:
    """Cell label (grade_id, or its index) -> seconds, for one run of ``lab``'s solved notebook."""
    nb = submissions.solved(lab)
    with tempfile.TemporaryDirectory() as folder:
        shutil.copytree(lab.release_notebook.parent, folder, dirs_exist_ok=True)
        client = NotebookClient(nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": folder}})
        seconds: dict[str, float] = {}
        with client.setup_kernel():
            for index, cell in enumerate(nb.cells):
                if cell.cell_type != "code":
                    continue
                start = time.perf_counter()
                client.execute_cell(cell, index)
                seconds[cells.meta(cell).get("grade_id") or f"cell {index}"] = time.perf_counter() - start
    return seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("labs", nargs="*", help="lab ids (default: every lab)")
    parser.add_argument("--repeat", type=int, default=3, help="runs per lab (default 3)")
    parser.add_argument("--top", type=int, default=5, help="slowest cells shown per lab (default 5)")
    args = parser.parse_args()
    labs = [get_lab(name) for name in args.labs] or all_labs()
    print(f"| lab | whole run (s) | slowest cells (s, share of the {CELL_LIMIT_S:g} s cell limit) |")
    print("|---|---|---|")
    for lab in labs:
        runs = [cell_seconds(lab) for _ in range(args.repeat)]
        median = {label: statistics.median(run[label] for run in runs) for label in runs[0]}
        whole = statistics.median(sum(run.values()) for run in runs)
        slowest = sorted(median.items(), key=lambda item: -item[1])[:args.top]
        shown = ", ".join(f"`{label}` {s:.1f} ({s / CELL_LIMIT_S:.0%})" for label, s in slowest)
        print(f"| `{lab.id}` | {whole:.1f} | {shown} |", flush=True)


if __name__ == "__main__":
    main()

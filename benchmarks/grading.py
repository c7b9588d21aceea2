"""Time the solved notebooks and the grading of the demo class.

    python benchmarks/grading.py [LAB ...]        (default: every lab)

Prints, per lab, the median time to execute the solved source notebook (3 runs, kernel start
included), then the wall time to grade the lab's demo class (blank, solved, one submission per
catalogued mistake) through nbgrader, in a temporary course.
"""

from __future__ import annotations

import statistics
import sys
import tempfile
import time
from pathlib import Path

import nbformat
from nbclient import NotebookClient

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from autograder.catalogues import submissions  # noqa: E402
from autograder.pipeline import grading, nbgrader_apps  # noqa: E402
from autograder.labs import all_labs, get_lab  # noqa: E402


def notebook_seconds(path: Path, runs: int = 3) -> float:
    times = []
    for _ in range(runs):
        nb = nbformat.read(path, as_version=4)
        start = time.perf_counter()
        NotebookClient(nb, timeout=600, resources={"metadata": {"path": str(path.parent)}}).execute()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main(lab_ids: list[str]) -> None:
    nbgrader_apps.course_config()  # puts the course root on the kernels' PYTHONPATH
    labs = [get_lab(i) for i in lab_ids] if lab_ids else all_labs()
    print(f"{'lab':<16}{'solved notebook [s]':>20}{'submissions':>13}{'grading [s]':>13}{'per submission [s]':>20}")
    for lab in labs:
        run = notebook_seconds(lab.source_notebook)
        with tempfile.TemporaryDirectory() as tmp:
            students = submissions.write_class([lab], Path(tmp) / "class")
            start = time.perf_counter()
            grading.grade(Path(tmp) / "class", Path(tmp) / "course")
            graded = time.perf_counter() - start
        print(f"{lab.id:<16}{run:>20.2f}{len(students):>13d}{graded:>13.1f}{graded / len(students):>20.2f}", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])

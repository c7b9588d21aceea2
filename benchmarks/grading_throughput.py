"""Grading throughput: a synthetic class graded with one process, then with two.

    python benchmarks/grading_throughput.py [--size 200] [--jobs 1 2] [LAB ...]   (default: every lab)

The class of each lab has ``size`` submissions: every catalogued fault once (hostile and careless
work: stuck, crashing, memory-hungry, unreadable, ...), every catalogued cheat once where the lab
has them, then the catalogued mistakes and the solved notebook in turn (honest work). It is graded
from scratch in a new course folder for each number of jobs, and the script prints submissions per
minute and the speed-up over one job, measured in the same run.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import itertools
import sys
import tempfile
import time
from pathlib import Path

import nbformat

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from autograder import cells, faults, grading, submissions  # noqa: E402
from autograder.labs import Lab, all_labs, get_lab  # noqa: E402
from autograder.mistakes import catalogue  # noqa: E402


def write_class(lab: Lab, size: int, folder: Path) -> dict[str, int]:
    """Write ``size`` submissions of ``lab``; how many of each kind."""
    blank = cells.blank_names(cells.read(lab.source_notebook))[0]
    hostile = faults.write_faults(lab, blank, folder)
    honest = itertools.cycle([submissions.solved(lab)] + [submissions.with_mistake(lab, m) for m in catalogue(lab)])
    for k in range(size - len(hostile)):
        path = folder / f"student{k:03d}" / lab.id / lab.notebook_name
        path.parent.mkdir(parents=True)
        nbformat.write(next(honest), path)
    return {"hostile or careless": len(hostile), "honest (solved or a catalogued mistake)": size - len(hostile)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("labs", nargs="*")
    parser.add_argument("--size", type=int, default=200)
    parser.add_argument("--jobs", type=int, nargs="+", default=[1, 2])
    args = parser.parse_args()
    labs = [get_lab(i) for i in args.labs] if args.labs else all_labs()
    print(f"{'lab':<16}{'submissions':>12}{'jobs':>6}{'wall [s]':>10}{'per minute':>12}{'speed-up':>10}")
    for lab in labs:
        with tempfile.TemporaryDirectory() as tmp:
            kinds = write_class(lab, args.size, Path(tmp) / "class")
            base = None
            for jobs in args.jobs:
                start = time.perf_counter()
                with contextlib.redirect_stdout(io.StringIO()):  # the grades table of 200 students
                    grading.grade(Path(tmp) / "class", Path(tmp) / f"course-{jobs}", jobs=jobs)
                wall = time.perf_counter() - start
                base = base or wall
                print(f"{lab.id:<16}{args.size:>12}{jobs:>6}{wall:>10.0f}{60 * args.size / wall:>12.1f}{base / wall:>10.2f}",
                      flush=True)
            print(f"  ({', '.join(f'{n} {kind}' for kind, n in kinds.items())})")


if __name__ == "__main__":
    main()

"""Grading throughput: a synthetic class graded with one process, then with two.

    python benchmarks/grading_throughput.py [--size 200] [--jobs 1 2] [LAB ...]   (default: every lab)

The class of each lab has ``size`` submissions (autograder/catalogues/synthetic_class.py): every catalogued
fault once (careless work: stuck, crashing, memory-hungry, unreadable, ...), every catalogued cheat
once (hostile work), then the solved notebook and the catalogued mistakes in turn (honest work). It
is graded from scratch in a new course folder for each number of jobs. The script prints
submissions per minute and the speed-up over one job, measured in the same run, and checks every
row against the catalogues: each fault costs what it should, each cheat earns nothing for what it
games and is flagged when it should be, and no honest submission is flagged or loses more than
its mistake.
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import io
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from autograder.catalogues import synthetic_class  # noqa: E402
from autograder.pipeline import grading  # noqa: E402
from autograder.labs import all_labs, get_lab  # noqa: E402


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
            outcomes = synthetic_class.write(lab, args.size, Path(tmp) / "class")
            base = None
            for jobs in args.jobs:
                start = time.perf_counter()
                with contextlib.redirect_stdout(io.StringIO()):  # the grades table of 200 students
                    rows = grading.grade(Path(tmp) / "class", Path(tmp) / f"course-{jobs}", jobs=jobs).rows
                wall = time.perf_counter() - start
                errors = synthetic_class.errors(rows, outcomes)
                base = base or wall
                print(f"{lab.id:<16}{args.size:>12}{jobs:>6}{wall:>10.0f}{60 * args.size / wall:>12.1f}{base / wall:>10.2f}",
                      flush=True)
                print(f"  {len(outcomes) - len(errors)} of {len(outcomes)} graded as catalogued",
                      *(f"\n  {error}" for errs in errors.values() for error in errs), flush=True)
            kinds = collections.Counter(outcome.kind for outcome in outcomes)
            print(f"  ({', '.join(f'{n} {kind}' for kind, n in kinds.items())})")


if __name__ == "__main__":
    main()

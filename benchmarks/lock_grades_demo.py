"""environment.lock makes an environment that grades the demo class to the same grades.

    python benchmarks/lock_grades_demo.py [LAB ...]   (default: every lab; run it with the kit's .venv)

For maintainers, after regenerating environment.lock and before a term. It makes a fresh virtual
environment from environment.lock alone (`pip install -r environment.lock`, then the kit itself
without dependencies), checks that it holds exactly the locked versions, grades the demo class of
the given labs there (`python -m autograder demo`'s class: blank, solved, every catalogued
mistake), grades the same class with the environment running this script, and compares the two
grades.csv files column by column. It prints the differences and exits 1 if there are any.
Several minutes: too slow for every CI run, so tests/test_versions.py checks only what can be
checked without installing (the lock pins exactly environment.txt's packages, within its ranges).
"""

from __future__ import annotations

import argparse
import csv
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from autograder.catalogues import submissions  # noqa: E402
from autograder.labs import all_labs, get_lab  # noqa: E402

GRADE = """
import sys
from pathlib import Path
from autograder.pipeline import grading  # noqa: E402
grading.grade(Path(sys.argv[1]), Path(sys.argv[2]), jobs=2)
"""

CHECK_LOCK = """
from autograder.pipeline import versions  # noqa: E402
differ = versions.differences_from_lock(versions.LOCK)
assert not differ, f"the environment made from environment.lock differs from it: {differ}"
"""


def run(command: list[str], **kwargs) -> None:
    subprocess.run(command, check=True, cwd=ROOT, **kwargs)


def grades(python: str, class_dir: Path, workdir: Path) -> dict[tuple[str, str], dict[str, str]]:
    """The class graded with ``python``: (student, lab) -> its grades.csv record."""
    run([python, "-c", GRADE, str(class_dir), str(workdir)], stdout=subprocess.DEVNULL)
    with open(workdir / "grades.csv", newline="") as handle:
        return {(r["student"], r["lab"]): r for r in csv.DictReader(handle)}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("labs", nargs="*")
    args = parser.parse_args()
    labs = [get_lab(i) for i in args.labs] if args.labs else all_labs()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        start = time.monotonic()
        run([sys.executable, "-m", "venv", str(folder / "venv")])
        python = str(folder / "venv" / "bin" / "python")
        run([python, "-m", "pip", "install", "--quiet", "-r", "environment.lock"])
        run([python, "-m", "pip", "install", "--quiet", "--no-deps", "-e", "."])
        run([python, "-c", CHECK_LOCK])
        print(f"environment from environment.lock: {time.monotonic() - start:.0f} s")
        submissions.write_class(labs, folder / "class")
        start = time.monotonic()
        locked = grades(python, folder / "class", folder / "locked")
        print(f"graded with the lock's environment: {len(locked)} rows, {time.monotonic() - start:.0f} s")
        start = time.monotonic()
        current = grades(sys.executable, folder / "class", folder / "current")
        print(f"graded with {sys.executable}: {len(current)} rows, {time.monotonic() - start:.0f} s")
    differences = [f"{key}: only in one of the two" for key in locked.keys() ^ current.keys()]
    for key in sorted(locked.keys() & current.keys()):
        differences += [f"{key} {column}: lock {value!r}, current {current[key].get(column)!r}"
                        for column, value in locked[key].items() if current[key].get(column) != value]
    print("\n".join(differences) or f"the same grades, every column of {len(locked)} rows")
    return 1 if differences else 0


if __name__ == "__main__":
    sys.exit(main())

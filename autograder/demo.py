"""The demo: release every lab, make a synthetic class, grade it and print the table."""

from __future__ import annotations

from pathlib import Path

from autograder import grading, submissions
from autograder.labs import ROOT, all_labs
from autograder.release import release_all

DEMO_DIR = ROOT / "demo"


def run_demo(workdir: Path = DEMO_DIR, jobs: int = 2) -> list[grading.GradeRow]:
    """Release all labs, write the demo class to ``workdir/class`` and grade it in ``workdir/course``
    with ``jobs`` processes."""
    labs = all_labs()
    release_all()
    class_dir = workdir / "class"
    students = submissions.write_class(labs, class_dir)
    print(f"Demo class: {len(students)} students in {class_dir} (blank, solved, and one per catalogued mistake).")
    return grading.grade(class_dir, workdir / "course", workdir / "grades.csv", jobs)

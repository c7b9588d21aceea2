"""python -m autograder: the instructor's pipeline. Run it from the course root."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from autograder.labs import ROOT


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m autograder", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)
    commands.add_parser("labs", help="list the labs: blanks, points, visible checks, hidden tests, catalogued mistakes, and the claims each checks")
    commands.add_parser("release", help="generate release/<lab>/ for every lab with nbgrader, then check it for leaks")
    bundle = commands.add_parser("bundle", help="write the solution-free tree that students get, and check it for leaks")
    bundle.add_argument("out", type=Path, help="a new folder")
    grade = commands.add_parser("grade", help="autograde SUBMISSIONS/<student>/<lab>/<lab>.ipynb; write grades and feedback")
    grade.add_argument("submissions", type=Path)
    grade.add_argument("--workdir", type=Path, default=ROOT, help="the nbgrader course folder to grade in (default: the course root)")
    grade.add_argument("--out", type=Path, default=None, help="the grades CSV (default: WORKDIR/grades.csv)")
    grade.add_argument("--jobs", type=int, default=1, help="grade this many submissions at a time (default 1)")
    demo = commands.add_parser("demo", help="release, make a synthetic class (blank, solved, every catalogued mistake), grade it")
    demo.add_argument("--workdir", type=Path, default=ROOT / "demo")
    demo.add_argument("--jobs", type=int, default=2, help="grade this many submissions at a time (default 2)")
    data = commands.add_parser("data", help="rebuild the shipped data in course/data/ from the seeded reference builds")
    data.add_argument("--check", action="store_true", help="only check that a rebuild reproduces the shipped files")
    collect = commands.add_parser("collect", help="turn an LMS download of one lab (a zip or a folder) into SUBMISSIONS/<student>/<lab>/ with nbgrader's zip_collect")
    collect.add_argument("lab")
    collect.add_argument("download", type=Path, help="the LMS download: a zip file or a folder of files named by student")
    collect.add_argument("--students", type=Path, required=True, help="CSV with the columns lms_name and student_id")
    collect.add_argument("--out", type=Path, required=True, help="the SUBMISSIONS folder to write")
    collect.add_argument("--pattern", default=None, help="regular expression for the LMS's file names, with the groups student_id and (optionally) timestamp")
    collect.add_argument("--timezone", default="UTC", help="the time zone of the submission times in file names (default: UTC)")
    similarity = commands.add_parser("similarity", help="list students' answers that are alike after normalisation, for review (changes no grade)")
    similarity.add_argument("folder", type=Path, help="a SUBMISSIONS folder, or a course folder that has submitted/")
    similarity.add_argument("--threshold", type=float, default=0.8, help="list pairs scoring at least this (1 = identical; default 0.8)")
    similarity.add_argument("--out", type=Path, default=None, help="also write the pairs to this CSV")
    args = parser.parse_args(argv)

    if args.command == "labs":
        from autograder.inventory import print_inventory
        from autograder.labs import all_labs

        print_inventory(all_labs())
    elif args.command == "release":
        from autograder.release import release_all

        release_all()
        print(f"Released to {ROOT / 'release'}; no leaks found.")
    elif args.command == "bundle":
        from autograder.bundle import write_bundle

        print(f"Student bundle written to {write_bundle(args.out)}; no leaks found.")
    elif args.command == "grade":
        from autograder.grading import grade as grade_submissions

        grade_submissions(args.submissions.resolve(), args.workdir.resolve(), args.out, args.jobs)
    elif args.command == "demo":
        from autograder.demo import run_demo

        run_demo(args.workdir.resolve(), args.jobs)
    elif args.command == "data":
        from autograder import data as shipped

        if args.check:
            stale = shipped.stale_files()
            print("The shipped data are reproduced exactly." if not stale else f"Stale: {', '.join(stale)}")
            return 1 if stale else 0
        for path in shipped.rebuild():
            print(f"wrote {path.relative_to(ROOT)}")
    elif args.command == "collect":
        from autograder.intake import run_collect

        return run_collect(args.lab, args.download, args.students, args.out, args.pattern, args.timezone)
    elif args.command == "similarity":
        from autograder.similarity import run_similarity

        return run_similarity(args.folder, args.threshold, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

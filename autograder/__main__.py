"""python -m autograder: the instructor's pipeline. Run it from the course root."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from typing import TYPE_CHECKING

from autograder import default_jobs
from autograder.labs import ROOT
from autograder.pipeline.archives import RATIO_FLOOR, Limits

if TYPE_CHECKING:
    from autograder.pipeline.shards import Shard

JOBS_HELP = "grade this many submissions at a time (default: the number of cores, %(default)s here)"


def _shard(spec: str) -> Shard:
    """``--shard K/N`` (argparse reports a ValueError's message as the argument's error)."""
    from autograder.pipeline.shards import parse_shard

    try:
        return parse_shard(spec)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def build_parser() -> argparse.ArgumentParser:
    """The command line: one subcommand per step of the pipeline, each argument with its help."""
    parser = argparse.ArgumentParser(prog="python -m autograder", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)
    commands.add_parser("labs", help="list each lab's blanks by name with their points and catalogued mistakes, and the claims the lab checks")
    commands.add_parser("release", help="generate release/<lab>/ for every lab with nbgrader, then check it for leaks")
    bundle = commands.add_parser("bundle", help="write the solution-free tree that students get, and check it for leaks")
    bundle.add_argument("out", type=Path, help="a new folder")
    grade = commands.add_parser("grade", help="autograde SUBMISSIONS/<student>/<lab>/<lab>.ipynb; write grades and feedback")
    grade.add_argument("submissions", type=Path, help="the folder of submissions, SUBMISSIONS/<student>/<lab>/<lab>.ipynb "
                       "(a <student> folder not named by a student id, letters, digits and _ . @ -, is skipped and listed)")
    grade.add_argument("--workdir", type=Path, default=ROOT, help="the nbgrader course folder to grade in (default: the course root)")
    grade.add_argument("--out", type=Path, default=None, help="the grades CSV (default: WORKDIR/grades.csv)")
    grade.add_argument("--jobs", type=int, default=default_jobs(), help=JOBS_HELP)
    grade.add_argument("--shard", type=_shard, default=None, metavar="K/N",
                       help="grade only the K-th of N parts of the class (split by student id), into a PostgreSQL "
                       "gradebook (GRADEBOOK_URL) that every part shares; the grades CSV defaults to "
                       "WORKDIR/grades-shard-K-of-N.csv (README: Large classes)")
    grade.add_argument("--require-sandbox", action="store_true",
                       help="refuse to start unless the grading kernels get the whole sandbox (both layers; README: "
                       "The grading kernel's sandbox); the cluster recipes set it")
    export = commands.add_parser("export", help="write the grades CSV of every submission in the gradebook, without "
                                 "grading again (as nbgrader export); fails, listing them, if some are not graded "
                                 "yet or their autograded notebooks and feedback pages are not in WORKDIR")
    export.add_argument("--workdir", type=Path, default=ROOT, help="the nbgrader course folder (default: the course root)")
    export.add_argument("--out", type=Path, default=None, help="the grades CSV (default: WORKDIR/grades.csv)")
    report = commands.add_parser("report", help="write the class report of each graded lab into WORKDIR/report/: "
                                 "an HTML page of counts (scores, each blank's full marks, catalogued mistakes, other "
                                 "losses and unwritten blanks, failing visible checks; flagged, late and faulted "
                                 "submissions; written answers "
                                 "waiting for a hand grade), its figure (PNG), the counts (CSV) and the students behind "
                                 "each count (<lab>-students.csv), read from the gradebook as export reads it")
    report.add_argument("--workdir", type=Path, default=ROOT, help="the nbgrader course folder (default: the course root)")
    audit = commands.add_parser("audit", help="list the graded test cells whose score came from the student's kernel "
                                "rather than from the grader's verdict (possible with versions before the verdicts; "
                                "README: Versions that graded wrongly), so that exactly those submissions are regraded")
    audit.add_argument("--workdir", type=Path, default=ROOT, help="the nbgrader course folder (default: the course root)")
    feedback = commands.add_parser("feedback", help="after grading written answers in formgrader: rewrite every "
                                   "feedback page and the grades CSV from the gradebook, without grading again")
    feedback.add_argument("--workdir", type=Path, default=ROOT, help="the nbgrader course folder (default: the course root)")
    feedback.add_argument("--out", type=Path, default=None, help="the grades CSV (default: WORKDIR/grades.csv)")
    demo = commands.add_parser("demo", help="grade a small synthetic class of each lab (blank, solved, "
                               "a few catalogued mistakes, a cheat, a fault) and check every row")
    demo.add_argument("--workdir", type=Path, default=ROOT / "demo", help="the folder for the class, its course and grades (default: demo/)")
    demo.add_argument("--jobs", type=int, default=default_jobs(), help=JOBS_HELP)
    demo.add_argument("--full", action="store_true", help="grade the whole catalogue instead: blank, solved and every "
                      "catalogued mistake of every lab (about 200 submissions, seven times the quick class)")
    data = commands.add_parser("data", help="rebuild the shipped data in course/data/ from the seeded reference builds")
    data.add_argument("--check", action="store_true", help="only check that a rebuild reproduces the shipped files")
    collect = commands.add_parser("collect", help="turn an LMS download of one lab (a zip or a folder) into SUBMISSIONS/<student>/<lab>/ with nbgrader's zip_collect")
    collect.add_argument("lab", help="the lab's id, e.g. train-kf")
    collect.add_argument("download", type=Path, help="the LMS download: a zip file or a folder of files named by student")
    collect.add_argument("--students", type=Path, required=True, help="CSV with the columns lms_name and student_id")
    collect.add_argument("--out", type=Path, required=True, help="the SUBMISSIONS folder to write")
    collect.add_argument("--pattern", default=None, help="regular expression for the LMS's file names, with the groups student_id and (optionally) timestamp")
    collect.add_argument("--times-in-names", action="store_true",
                         help="the LMS writes each upload's time after the student's name, <name>_<YYYY-MM-DD-HH-MM-SS>_<the "
                              "student's file name>: read it (without this no time is read from a name, since the "
                              "student chooses what follows the LMS's name)")
    collect.add_argument("--timezone", default="UTC", help="the time zone of the submission times in file names (default: UTC)")
    limits = Limits()
    collect.add_argument("--max-total-mb", type=float, default=limits.max_bytes / 1e6, metavar="MB",
                         help="refuse an archive that would take what the download unpacks past this many MB in all "
                         "(default: %(default)g)")
    collect.add_argument("--max-file-mb", type=float, default=limits.max_file_bytes / 1e6, metavar="MB",
                         help="refuse a member of an archive that unpacks to more than this many MB (default: %(default)g)")
    collect.add_argument("--max-files", type=int, default=limits.max_files, metavar="N",
                         help="refuse an archive that would take the files the download unpacks past this many in all "
                         "(default: %(default)s)")
    collect.add_argument("--max-ratio", type=float, default=limits.max_ratio, metavar="R",
                         help=f"refuse what unpacks to more than {RATIO_FLOOR / 1e6:g} MB at more than this many times its "
                         "compressed size (default: %(default)g). Archives inside archives, links, and paths that leave "
                         "the folder are always refused")
    similarity = commands.add_parser("similarity", help="list students' answers that are alike after normalisation, for review (changes no grade)")
    similarity.add_argument("folder", type=Path, help="a SUBMISSIONS folder, or a course folder that has submitted/")
    similarity.add_argument("--threshold", type=float, default=0.8, help="list pairs scoring at least this (1 = identical; default 0.8)")
    similarity.add_argument("--out", type=Path, default=None, help="also write the pairs to this CSV")
    new = commands.add_parser("new", help="write the files of a new lab from the template lab, which passes every "
                              "test once built: its draft notebook and hidden code (solutions/<module>/), its course "
                              "module, its due date and its row in README's table of the labs")
    new.add_argument("lab", help="the new lab's id: lower-case words joined by hyphens, e.g. scalar-kf")
    new.add_argument("--topic", help="name its course module course/TOPIC.py for what it holds (default: the lab's "
                     "module name, e.g. scalar_kf)")
    new.add_argument("--data", action="store_true", help="the lab ships data: a seeded build (write_data) in its "
                     "reference, load() in its course module, and a test that the shipped data are a fresh build")
    build = commands.add_parser("build", help="make a lab's source notebook from its draft (solutions/<module>/draft.py), "
                                "run it, name each cell that fails, release it and list what it holds")
    build.add_argument("lab", help="the lab's id, e.g. scalar-kf")
    build.add_argument("--keep-data", action="store_true", help="use the lab's shipped data as they are instead of "
                       "rebuilding them first (a rebuild takes minutes for some labs); for a change to the draft alone")
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)

    if args.command == "new":
        from autograder.authoring.new import new_lab, next_steps
        from autograder.labs import Lab

        try:
            written = new_lab(args.lab, args.topic, args.data)
        except ValueError as error:
            print(f"new: {error}", file=sys.stderr)
            return 1
        print("\n".join(f"wrote {path.relative_to(ROOT)}" for path in written))
        print(next_steps(Lab(args.lab), args.topic or Lab(args.lab).module))
    elif args.command == "build":
        from autograder.authoring.build import build_lab
        from autograder.labs import Lab

        try:
            return 0 if build_lab(Lab(args.lab), args.keep_data) else 1
        except FileNotFoundError as error:
            print(f"build: {error}", file=sys.stderr)
            return 1
    elif args.command == "labs":
        from autograder.authoring.inventory import print_inventory
        from autograder.labs import all_labs

        print_inventory(all_labs())
    elif args.command == "release":
        from autograder.release.notebooks import release_all

        release_all()
        print(f"Released to {ROOT / 'release'}; no leaks found.")
    elif args.command == "bundle":
        from autograder.release.bundle import write_bundle

        print(f"Student bundle written to {write_bundle(args.out)}; no leaks found.")
    elif args.command == "grade":
        from autograder.pipeline.grading import SandboxIncomplete
        from autograder.pipeline.grading import grade as grade_submissions
        from autograder.pipeline.shards import NotShared, TooFewConnections

        try:
            graded = grade_submissions(args.submissions.resolve(), args.workdir.resolve(), args.out, args.jobs,
                                       args.shard, args.require_sandbox)
        except (NotShared, SandboxIncomplete, TooFewConnections) as error:
            print(f"grade: {error}", file=sys.stderr)
            return 1
        if graded.problems():
            # a scheduler (Slurm, a Kubernetes Job) then sees the task fail, and its retry grades what is missing
            print(f"grade: not everything given was graded: {graded.problems()}.", file=sys.stderr)
            return 1
    elif args.command == "export":
        from autograder.pipeline.export import export_course, incomplete

        workdir = args.workdir.resolve()
        out = args.out or workdir / "grades.csv"
        rows, missing = export_course(workdir, out)
        print(f"Exported the grades of {len(rows)} submissions to {out}.")
        if missing:
            print(incomplete(missing, out), file=sys.stderr)
            return 1
    elif args.command == "report":
        from autograder.pipeline.class_report import write_report
        from autograder.pipeline.export import course_rows

        workdir = args.workdir.resolve()
        rows, missing = course_rows(workdir)
        for page in write_report(workdir, rows):
            print(f"Class report: {page}")
        if missing:
            print(f"The report leaves out {len(missing)} submissions of the gradebook, not graded yet or not gathered "
                  "into this course folder:\n  " + "\n  ".join(missing), file=sys.stderr)
            return 1
    elif args.command == "audit":
        from autograder.pipeline.audit import run_audit

        return run_audit(args.workdir.resolve())
    elif args.command == "feedback":
        from autograder.pipeline.feedback import regenerate

        workdir = args.workdir.resolve()
        rows = regenerate(workdir, args.out)
        from course.checks import count

        print(f"Rewrote the feedback of {count(len(rows), 'graded submission')} in {workdir / 'feedback'} "
              f"and the grades in {args.out or workdir / 'grades.csv'}.")
    elif args.command == "demo":
        from autograder.catalogues.demo import run_demo

        return 0 if run_demo(args.workdir.resolve(), args.jobs, args.full) else 1
    elif args.command == "data":
        from autograder.release import data as shipped

        if args.check:
            stale = shipped.stale_files()
            print("The shipped data are reproduced exactly." if not stale else f"Stale: {', '.join(stale)}")
            return 1 if stale else 0
        for path in shipped.rebuild():
            print(f"wrote {path.relative_to(ROOT)}")
    elif args.command == "collect":
        from autograder.pipeline.collect import run_collect

        limits = Limits(round(args.max_total_mb * 1e6), round(args.max_file_mb * 1e6), args.max_files, args.max_ratio)
        return run_collect(args.lab, args.download, args.students, args.out, args.pattern, args.timezone, limits,
                           args.times_in_names)
    elif args.command == "similarity":
        from autograder.integrity.similarity import run_similarity

        return run_similarity(args.folder, args.threshold, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

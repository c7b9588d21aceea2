"""One class graded by 1, 2 and 4 concurrent shards, and how many submissions the gradebook can take.

    python benchmarks/shards.py [--size 20] [--shards 1 2 4] [--repeat 3] [--writers 1 4 8]

The class is tests/test_shards.py's: ``size`` submissions of each of train-kf and nonlinear-filters
(the demo's blank, solved, two catalogued mistakes, a cheat and a fault per lab, then honest
work). For each number of shards N, in a fresh database on a PostgreSQL server on loopback
(tests/postgres_server.py) and a fresh shared course folder, N processes ``grade --shard K/N --jobs
1`` start at once; the time is the wall time until the last one ends. ``export`` then writes
grades.csv, which must be the same for every N and every repeat, with every row as catalogued. The
script prints the median over ``repeat`` runs and the speed-up over one shard, measured in the same
run.

The gradebook's write rate. Each grading run also counts the transactions the server committed
per graded submission (``pg_stat_database``). Then ``writers`` processes at once do, for ``seconds``,
what a grading process does to the gradebook for every submission, on the graded class: open the
gradebook as nbgrader does (a new connection, its table and course checks), find a submission's
notebook with its grades, write a score into each grade, and commit. Their rate, in commits per
second, divided by the commits of one graded submission, is the number of submissions per second
the gradebook can take: the limit on how many grading processes, on any number of machines, one
gradebook serves. The server's CPU time (its processes' times from /proc, on this machine) is
counted for each graded submission, for the write loop, and for a fresh open of nbgrader's
gradebook alone, which nbgrader does at every step.
"""

from __future__ import annotations

import argparse
import contextlib
import multiprocessing
import os
import random
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

import postgres_server  # noqa: E402
import shard_runs  # noqa: E402
from gradebook_sql import query  # noqa: E402
from nbgrader.api import Gradebook  # noqa: E402
from sqlalchemy.engine import make_url  # noqa: E402

from autograder.catalogues import demo  # noqa: E402
from autograder.labs import get_lab  # noqa: E402
from autograder.pipeline import grades, grading, intake  # noqa: E402

LABS = [get_lab("train-kf"), get_lab("nonlinear-filters")]


def server_cpu(db_url: str) -> float:
    """CPU seconds used so far by the PostgreSQL server of ``db_url`` on this machine: its postmaster
    (found by its port) and its processes, and the processes that ended (the postmaster's children's
    times)."""
    port, tick = str(make_url(db_url).port), os.sysconf("SC_CLK_TCK")
    stats = {}
    for proc in Path("/proc").glob("[0-9]*"):
        with contextlib.suppress(OSError):
            fields = (proc / "stat").read_text().rsplit(")", 1)[1].split()
            stats[int(proc.name)] = (int(fields[1]), [int(f) for f in fields[11:15]], (proc / "cmdline").read_bytes())
    [postmaster] = [pid for pid, (_, _, cmd) in stats.items() if cmd.split(b"\0")[:1] != [b""]
                    and cmd.split(b"\0")[0].endswith(b"postgres") and port.encode() in cmd.split(b"\0")]
    times = [t for pid, (parent, t, _) in stats.items() if pid == postmaster or parent == postmaster]
    return sum(sum(t) for t in times) / tick


def commits(db_url: str) -> int:
    """Transactions committed so far in the database of ``db_url`` (all connections)."""
    [row] = query(db_url, "SELECT xact_commit FROM pg_stat_database WHERE datname = current_database()")
    return row["xact_commit"]


def grade_in_shards(class_dir: Path, folder: Path, db_url: str, count: int) -> float:
    """Grade the class with ``count`` concurrent shards in the course ``folder``; the wall time."""
    start = time.perf_counter()
    runs = [shard_runs.start_grade(class_dir, folder, db_url, folder.parent / f"{folder.name}-{k}.log",
                                   "--shard", f"{k}/{count}", "--jobs", "1") for k in range(1, count + 1)]
    for run in runs:
        run.finish(timeout=3600)
    return time.perf_counter() - start


def set_up_at_once(class_dir: Path, folder: Path, db_url: str, count: int) -> float:
    """The wall time of ``count`` processes that set the class up at once in a fresh gradebook
    (grading.set_up, each in a course folder of its own; the processes' start included): they take
    the set-up lock in turn."""
    by_lab = intake.class_list(class_dir, LABS)
    os.environ["GRADEBOOK_URL"] = db_url  # the spawned processes inherit it
    with multiprocessing.get_context("spawn").Pool(count) as pool:
        start = time.perf_counter()
        pool.starmap(grading.set_up, [(LABS, folder / f"course-{k}", by_lab) for k in range(count)])
        return time.perf_counter() - start


def open_cost(db_url: str, opens: int = 100) -> tuple[float, float]:
    """The server's CPU seconds and the commits of one fresh open of nbgrader's gradebook, as every
    step of nbgrader opens it (averaged over ``opens``)."""
    cpu, committed = server_cpu(db_url), commits(db_url)
    for _ in range(opens):
        Gradebook(db_url, "estimation-lab-kit").close()
    time.sleep(1.5)
    return (server_cpu(db_url) - cpu) / opens, (commits(db_url) - committed) / opens


def write_rounds(db_url: str, keys: list[tuple[str, str]], seconds: float, seed: int) -> int:
    """What grading does to the gradebook per submission, over and over for ``seconds``, on random
    submissions of ``keys`` (student, lab); how many rounds."""
    rng, rounds, deadline = random.Random(seed), 0, time.perf_counter() + seconds
    while time.perf_counter() < deadline:
        student, lab = rng.choice(keys)
        with Gradebook(db_url, "estimation-lab-kit") as gb:
            notebook = gb.find_submission_notebook(lab, lab, student)
            for grade in notebook.grades:
                grade.auto_score = rng.random() * (grade.max_score or 1.0)
            gb.db.commit()
        rounds += 1
    return rounds


def write_rate(db_url: str, keys: list[tuple[str, str]], writers: int, seconds: float) -> float:
    """Commits per second of ``writers`` processes doing ``write_rounds`` at once."""
    before = commits(db_url)
    with multiprocessing.get_context("spawn").Pool(writers) as pool:
        pool.starmap(write_rounds, [(db_url, keys, seconds, seed) for seed in range(writers)])
    time.sleep(1.5)  # PostgreSQL publishes a backend's counts within a second of its last transaction
    return (commits(db_url) - before) / seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=20, help="submissions per lab (default 20: 40 in all)")
    parser.add_argument("--shards", type=int, nargs="+", default=[1, 2, 4])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--writers", type=int, nargs="+", default=[1, 4, 8])
    parser.add_argument("--seconds", type=float, default=20.0, help="how long each write-rate measurement runs")
    args = parser.parse_args()
    print(f"{os.cpu_count()} cores; each shard grades one submission at a time (--jobs 1).", flush=True)
    with tempfile.TemporaryDirectory() as tmp, postgres_server.running_server() as server:
        class_dir = Path(tmp) / "class"
        expected = demo.write_demo_class(LABS, class_dir, size=args.size)
        walls: dict[int, list[float]] = {n: [] for n in args.shards}
        per_submission, cpu_per_submission, reference, db_url = [], [], None, None
        for repeat in range(args.repeat):
            for count in args.shards:
                name = f"shards{count}-run{repeat}"
                db_url, folder = shard_runs.new_database(server, name), Path(tmp) / name
                before, cpu = commits(db_url), server_cpu(db_url)
                walls[count].append(grade_in_shards(class_dir, folder, db_url, count))
                time.sleep(1.5)
                per_submission.append((commits(db_url) - before) / len(expected))
                cpu_per_submission.append((server_cpu(db_url) - cpu) / len(expected))
                exported = shard_runs.export(folder, db_url)
                table = shard_runs.csv_rows(folder / "grades.csv")
                os.environ["GRADEBOOK_URL"] = db_url
                differ = demo.unexpected(grades.read_grades(folder, LABS), expected)
                reference = reference or table
                print(f"  {count} shards, run {repeat + 1}: {walls[count][-1]:.0f} s; export exit {exported.returncode}; "
                      f"{'grades.csv as in the first run' if table == reference else 'GRADES.CSV DIFFERS'}; "
                      f"{len(expected) - len(differ)} of {len(expected)} rows as catalogued", *differ, flush=True)
        one = statistics.median(walls[args.shards[0]])
        print(f"\n{len(expected)} submissions of {', '.join(lab.id for lab in LABS)}; median of {args.repeat} runs:")
        print(f"{'shards':>8}{'wall [s]':>10}{'per minute':>12}{'speed-up':>10}")
        for count in args.shards:
            wall = statistics.median(walls[count])
            print(f"{count:>8}{wall:>10.0f}{60 * len(expected) / wall:>12.1f}{one / wall:>10.2f}")

        for count in args.shards:
            wall = set_up_at_once(class_dir, Path(tmp) / f"set-up-{count}", shard_runs.new_database(server, f"set-up-{count}"),
                                  count)
            print(f"{count} shards set up at once: {wall:.1f} s ({wall / count:.1f} s each, one at a time)", flush=True)

        cost, cpu = statistics.median(per_submission), statistics.median(cpu_per_submission)
        print(f"\nThe gradebook: {cost:.0f} commits and {1000 * cpu:.0f} ms of the server's CPU per graded submission "
              f"(set-up included; median over the grading runs): one core of the server takes {1 / cpu:.0f} "
              "submissions per second.")
        open_cpu, open_commits = open_cost(db_url)
        print(f"A fresh open of nbgrader's gradebook alone: {1000 * open_cpu:.0f} ms of the server's CPU and "
              f"{open_commits:.0f} commits.")
        print(f"{'writers':>8}{'commits/s':>11}{'submissions/s':>15}{'server CPU':>12}")
        keys = list(expected)
        for writers in args.writers:
            before = server_cpu(db_url)
            rate = write_rate(db_url, keys, writers, args.seconds)
            busy = (server_cpu(db_url) - before) / args.seconds
            print(f"{writers:>8}{rate:>11.0f}{rate / cost:>15.1f}{busy:>11.0%}", flush=True)


if __name__ == "__main__":
    main()

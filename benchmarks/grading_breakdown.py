"""Where grading a solved submission spends its time, against a plain execution of the same notebook.

    python benchmarks/grading_breakdown.py [--submissions 8] [LAB ...]     (default: every lab)

For each lab, a class of solved submissions (one warm-up, then ``--submissions`` measured) is graded
by ``python -m autograder grade``'s own code with one job, in this process. Just before each
submission is graded, its notebook is executed plainly: nbclient, one kernel start, no sandbox, no
hidden tests, in a copy of its folder. The two alternate, so that both see the same load on a
shared machine. The script prints, per lab, the medians of the plain run, of grading (nbgrader's
autograde and its feedback page) and of their ratio per submission, then the grading time split into
phases, each counted once (a phase inside another is taken out of the outer one):

    kernel start  starting the sandboxed kernel and installing the grader's kernel-side module
    executing     the notebook's cells in the kernel (a test cell's visible part included)
    comparing     hidden tests: the grader's checks, their calls of the student's function, the
                  forked child that confines them
    shutdown      stopping the kernel and its sandbox
    gradebook     nbgrader's database: opening it, its statements and commits (a wait for its lock
                  included)
    feedback      the student's feedback page, less its gradebook time
    nbgrader      the rest of autograde: reading, sanitizing, scanning and writing notebooks, copies

and ``idle``: the part of grading during which neither the grader nor any kernel or child of it
was on a CPU (waits on sockets, sleeps, locks, disk), from the processes' CPU times.
The warm-up submission's grading (one-off imports and the reference's ``prepare``) is printed apart.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import shutil
import statistics
import sys
import tempfile
import time
from collections import defaultdict
from collections.abc import Callable, Iterator
from pathlib import Path

import nbformat
import psutil
from nbclient import NotebookClient
from nbgrader.api import Gradebook
from nbgrader.converters import GenerateFeedback
from sqlalchemy import event
from sqlalchemy.engine import Engine
from sqlalchemy.orm import Session

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from autograder.catalogues import submissions  # noqa: E402
from autograder.labs import Lab, all_labs, get_lab  # noqa: E402
from autograder.pipeline import grading  # noqa: E402
from autograder.pipeline.execute import GradingExecute  # noqa: E402

PHASES = ("kernel start", "executing", "comparing", "shutdown", "gradebook", "feedback", "nbgrader")


class Phases:
    """Exclusive wall time per phase: time goes to the innermost phase entered."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = defaultdict(float)
        self.kernel_cpu = 0.0
        """CPU seconds of the kernels, read just before each is shut down."""
        self._stack: list[str] = []
        self._since = time.perf_counter()

    def _switch(self) -> None:
        now = time.perf_counter()
        if self._stack:
            self.seconds[self._stack[-1]] += now - self._since
        self._since = now

    @contextlib.contextmanager
    def phase(self, name: str) -> Iterator[None]:
        self._switch()
        self._stack.append(name)
        try:
            yield
        finally:
            self._switch()
            self._stack.pop()

    def take(self) -> tuple[dict[str, float], float]:
        """The seconds counted since the last take, per phase, and the kernels' CPU seconds; starts afresh."""
        taken = dict(self.seconds), self.kernel_cpu
        self.seconds, self.kernel_cpu = defaultdict(float), 0.0
        return taken


def process_tree_cpu(pid: int) -> float:
    """CPU seconds used so far by process ``pid`` and every process below it (and what they reaped)."""
    try:
        root = psutil.Process(pid)
        tree = [root, *root.children(recursive=True)]
    except psutil.NoSuchProcess:
        return 0.0
    total = 0.0
    for process in tree:
        with contextlib.suppress(psutil.NoSuchProcess):  # it ended while the tree was read
            t = process.cpu_times()
            total += t.user + t.system + t.children_user + t.children_system
    return total


def _timed(phases: Phases, name: str, function: Callable) -> Callable:
    def wrapper(*args, **kwargs):
        with phases.phase(name):
            return function(*args, **kwargs)
    return wrapper


@contextlib.contextmanager
def instrumented(phases: Phases) -> Iterator[None]:
    """Count the grading pipeline's phases into ``phases`` while the block runs (see the module doc)."""
    patches = [
        (GradingExecute, "start_new_kernel", "kernel start"),
        (GradingExecute, "start_new_kernel_client", "kernel start"),
        (GradingExecute, "execute_cell", "executing"),
        (GradingExecute, "_execute_test_cell", "comparing"),
        (GradingExecute, "_cleanup_kernel", "shutdown"),
        (Gradebook, "__init__", "gradebook"),
        (Gradebook, "close", "gradebook"),
        (Session, "commit", "gradebook"),
        (GenerateFeedback, "start", "feedback"),
    ]
    originals = [(owner, name, owner.__dict__[name]) if name in owner.__dict__ else (owner, name, None)
                 for owner, name, _ in patches]
    for owner, name, phase in patches:
        setattr(owner, name, _timed(phases, phase, getattr(owner, name)))
    cleanup = GradingExecute._cleanup_kernel

    def cleanup_counting_cpu(client: GradingExecute) -> None:
        # the sandbox's init does not pass its kernel's CPU time up to the grader: read it while it runs
        if client.km is not None and client.km.has_kernel:
            phases.kernel_cpu += process_tree_cpu(client.km.provisioner.pid)
        cleanup(client)

    GradingExecute._cleanup_kernel = cleanup_counting_cpu

    def before(*_args):
        phases._switch()
        phases._stack.append("gradebook")

    def after(*_args):
        phases._switch()
        phases._stack.pop()

    event.listen(Engine, "before_cursor_execute", before)
    event.listen(Engine, "after_cursor_execute", after)
    try:
        yield
    finally:
        event.remove(Engine, "before_cursor_execute", before)
        event.remove(Engine, "after_cursor_execute", after)
        for owner, name, original in originals:
            if original is None:
                delattr(owner, name)
            else:
                setattr(owner, name, original)


def cpu_seconds() -> float:
    """CPU time of this process and of every child it has waited for (the hidden tests' checks), seconds."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def plain_seconds(notebook: Path) -> float:
    """Wall time of a plain nbclient run of ``notebook`` (one kernel start), in a copy of its folder."""
    with tempfile.TemporaryDirectory() as folder:
        shutil.copytree(notebook.parent, folder, dirs_exist_ok=True)
        nb = nbformat.read(notebook, as_version=4)
        start = time.perf_counter()
        NotebookClient(nb, timeout=600, resources={"metadata": {"path": folder}}).execute()
        return time.perf_counter() - start


def measure(lab: Lab, n: int) -> tuple[list[dict[str, float]], dict[str, float]]:
    """Grade one warm-up and ``n`` solved submissions of ``lab``; each measured one's row, and the warm-up's."""
    rows: list[dict[str, float]] = []
    phases = Phases()
    grade_student = grading._grade_student

    def measured(workdir: Path, lab_id: str, student: str, submitted: str) -> tuple[str, bool, bool]:
        plain = plain_seconds(workdir / submitted / student / lab_id / lab.notebook_name)
        phases.take()
        cpu, start = cpu_seconds(), time.perf_counter()
        with phases.phase("nbgrader"):
            log = grade_student(workdir, lab_id, student, submitted)
        wall = time.perf_counter() - start
        seconds, kernel_cpu = phases.take()
        rows.append({"plain": plain, "grading": wall, "idle": max(0.0, wall - (cpu_seconds() - cpu) - kernel_cpu), **seconds})
        return log

    with tempfile.TemporaryDirectory() as tmp:
        solved = submissions.solved(lab)
        for k in range(n + 1):
            submissions.write(solved, Path(tmp) / "class", f"solved-{k:02d}", lab)
        grading._grade_student = measured
        try:
            with instrumented(phases), contextlib.redirect_stdout(io.StringIO()):
                grading.grade(Path(tmp) / "class", Path(tmp) / "course", jobs=1)
        finally:
            grading._grade_student = grade_student
    return rows[1:], rows[0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("labs", nargs="*")
    parser.add_argument("--submissions", type=int, default=8)
    args = parser.parse_args()
    labs = [get_lab(i) for i in args.labs] if args.labs else all_labs()
    columns = ("plain", "grading", "ratio", *PHASES, "idle")
    print(f"medians over {args.submissions} solved submissions per lab, seconds (ratio: grading / plain, per submission)")
    print(f"{'lab':<18}" + "".join(f"{c:>13}" for c in columns))
    for lab in labs:
        rows, warm_up = measure(lab, args.submissions)
        for row in rows:
            row["ratio"] = row["grading"] / row["plain"]
        medians = {c: statistics.median(row.get(c, 0.0) for row in rows) for c in columns}
        print(f"{lab.id:<18}" + "".join(f"{medians[c]:>13.2f}" for c in columns), flush=True)
        print(f"{'  (warm-up)':<18}{warm_up['plain']:>13.2f}{warm_up['grading']:>13.2f}", flush=True)


if __name__ == "__main__":
    main()

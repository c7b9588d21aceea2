"""Running `python -m autograder grade` and `export` as an instructor's batch system does: each run a
process of its own (in a session of its own, so that it can be killed with its kernels), from the
course root, with GRADEBOOK_URL set to its database. tests/test_shards.py and benchmarks/shards.py
use them on the server of tests/postgres_server.py.
"""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import psycopg
from sqlalchemy.engine import make_url

from autograder.labs import ROOT


def new_database(server_url: str, name: str) -> str:
    """Create the empty database ``name`` on the server of ``server_url``; its SQLAlchemy URL."""
    url = make_url(server_url)
    with psycopg.connect(host=url.host, port=url.port, user=url.username, password=url.password,
                         dbname=url.database, autocommit=True) as connection:
        connection.execute(f'CREATE DATABASE "{name}"')
    return url.set(database=name).render_as_string(hide_password=False)


def environment(db_url: str | None) -> dict[str, str]:
    """This process's environment with GRADEBOOK_URL set to ``db_url`` (None: unset, SQLite)."""
    return {k: v for k, v in os.environ.items() if k != "GRADEBOOK_URL"} | ({"GRADEBOOK_URL": db_url} if db_url else {})


@dataclass
class Run:
    """A `python -m autograder grade` running, and the file its output goes to."""

    process: subprocess.Popen
    log: Path

    def finish(self, timeout: float = 900) -> None:
        """Wait for it; raise, with the end of its output, if it fails."""
        if self.process.wait(timeout=timeout) != 0:
            raise AssertionError(f"{' '.join(self.process.args[2:])} exited with {self.process.returncode}:\n"
                                 f"{self.log.read_text()[-3000:]}")

    def kill(self) -> None:
        """SIGKILL it and everything in its session, as a batch system ends a job."""
        os.killpg(self.process.pid, signal.SIGKILL)
        self.process.wait()


def start_grade(class_dir: Path, workdir: Path, db_url: str | None, log: Path, *options: str) -> Run:
    """Start `python -m autograder grade CLASS --workdir WORKDIR OPTIONS`, its output into ``log``."""
    with open(log, "w") as handle:
        process = subprocess.Popen(
            [sys.executable, "-m", "autograder", "grade", str(class_dir), "--workdir", str(workdir), *options],
            cwd=ROOT, env=environment(db_url), stdout=handle, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
            start_new_session=True)
    return Run(process, log)


def run_command(command: str, workdir: Path, db_url: str) -> subprocess.CompletedProcess:
    """`python -m autograder COMMAND --workdir WORKDIR` (its exit status is not checked)."""
    return subprocess.run([sys.executable, "-m", "autograder", command, "--workdir", str(workdir)], cwd=ROOT,
                          env=environment(db_url), capture_output=True, text=True, timeout=300)


def export(workdir: Path, db_url: str) -> subprocess.CompletedProcess:
    """`python -m autograder export --workdir WORKDIR` (its exit status is not checked)."""
    return run_command("export", workdir, db_url)


def report(workdir: Path, db_url: str) -> subprocess.CompletedProcess:
    """`python -m autograder report --workdir WORKDIR`, the class report after `export` (not checked either)."""
    return run_command("report", workdir, db_url)


def csv_rows(path: Path) -> list[list[str]]:
    """grades.csv as a list of rows, header first, in the file's order."""
    with open(path, newline="") as handle:
        return list(csv.reader(handle))

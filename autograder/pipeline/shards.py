"""One class graded by several processes or machines against one gradebook: ``grade --shard K/N``.

The split. Shard K of N grades the students whose id hashes (SHA-256, the same on every machine
and in every Python) to K: a student's labs go to one shard, the split does not depend on which
files are present, and each shard gets about 1/N of every lab's submissions, so that the slow
labs are spread over the shards as evenly as the fast ones.

The gradebook. nbgrader looks a row up, then inserts it, in separate transactions, and creates its
tables the same way. Several processes that do this at once on an empty or new gradebook fail
(PostgreSQL 18, four processes at once): the tables (a unique violation in ``pg_type``, or
``alembic_version`` created twice), the course, each student and each lab (``course_pkey``,
``student_pkey``, ``assignment_name_key``), and ``generate_assignment``, which deletes a lab's
notebook and cells and writes them again while the lab has no submissions (a foreign-key violation
in the process writing the cells, or a submission that would get only part of the cells). So every
``grade`` sets the class up, in one process at a time, under an advisory lock of the database
server (``gradebook_lock``), which holds across machines and which the server releases when its
holder's connection ends, also when the holder dies: the tables, the labs and their cells, the due
dates, and a row for every student and submission of the class that the gradebook lacks. Once a lab
has a submission, nbgrader updates its cells in place instead of deleting them. A grading process
then only updates its own submission's rows, under a lock of that submission, so that overlapping
shards grade a submission one after the other, never at once.
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from nbgrader.api import Gradebook
from sqlalchemy import create_engine, text
from sqlalchemy.engine import make_url
from sqlalchemy.pool import NullPool

SET_UP = "set-up"
"""The name of the lock held while a ``grade`` sets the class up in the gradebook."""


@dataclass(frozen=True)
class Shard:
    """Part ``index`` of ``count`` (1 <= index <= count) of a class."""

    index: int
    count: int

    def __str__(self) -> str:
        return f"{self.index}/{self.count}"

    @property
    def suffix(self) -> str:
        """What the names of this shard's own files end with: ``-shard-K-of-N``."""
        return f"-shard-{self.index}-of-{self.count}"

    def takes(self, student: str) -> bool:
        """Whether this shard grades ``student``'s submissions."""
        return shard_of(student, self.count) == self.index


def parse_shard(spec: str) -> Shard:
    """``"K/N"`` as a Shard; ValueError, saying what is expected, for anything else."""
    index, _, count = spec.partition("/")
    if not (index.isdigit() and count.isdigit() and 1 <= int(index) <= int(count)):
        raise ValueError(f"{spec!r} is not a shard: give K/N, the K-th of N parts of the class, with 1 <= K <= N "
                         "(e.g. 2/4)")
    return Shard(int(index), int(count))


def shard_of(student: str, count: int) -> int:
    """The shard (1 to ``count``) that grades ``student``: the student id's SHA-256, modulo ``count``."""
    digest = hashlib.sha256(student.encode()).digest()
    return int.from_bytes(digest[:8], "big") % count + 1


def lock_key(name: str) -> int:
    """The 64-bit key of PostgreSQL's advisory lock ``name`` (the kit's own, by its SHA-256)."""
    return int.from_bytes(hashlib.sha256(f"estimation-lab-kit {name}".encode()).digest()[:8], "big", signed=True)


class NotShared(RuntimeError):
    """The gradebook is not one that shards on several machines can share; the message says what to do."""


def is_server(db_url: str) -> bool:
    """Whether the gradebook at ``db_url`` is in PostgreSQL, which several machines can share."""
    return make_url(db_url).get_backend_name() == "postgresql"


def require_server(db_url: str) -> None:
    """Raise NotShared unless the gradebook at ``db_url`` is in PostgreSQL."""
    if not is_server(db_url):
        raise NotShared("--shard needs a gradebook that every shard reaches: set GRADEBOOK_URL to a PostgreSQL "
                        "database (README: PostgreSQL gradebook). The SQLite gradebook is a file of one machine.")


CONNECTIONS_PER_PROCESS = 2
"""Connections to the gradebook that one grading process holds at once: its submission's lock and nbgrader's
(measured). ``grade --jobs c`` grades in c processes (one, in its own, with ``--jobs 1``)."""


class TooFewConnections(RuntimeError):
    """The gradebook's server would refuse some of the connections that grading opens; the message says how
    to raise its limit."""


def free_connections(db_url: str) -> tuple[int, int]:
    """(the server's ``max_connections``, how many more connections it accepts now from the user of
    ``db_url``): its limit, less the connections open now, this one aside (pg_stat_database counts them
    for every user; pg_stat_activity hides other users' rows), less the slots that it keeps for
    superusers (``superuser_reserved_connections``, and ``reserved_connections`` since PostgreSQL 16)
    unless that user is one."""
    engine = create_engine(db_url, poolclass=NullPool)
    try:
        with engine.connect() as connection:
            limit, reserved, superuser, in_use = connection.execute(text(
                "SELECT current_setting('max_connections')::int,"
                " current_setting('superuser_reserved_connections')::int"
                " + coalesce(current_setting('reserved_connections', true)::int, 0),"
                " (SELECT rolsuper FROM pg_roles WHERE rolname = current_user),"
                " (SELECT sum(numbackends)::int FROM pg_stat_database)")).one()
    finally:
        engine.dispose()
    return limit, limit - (in_use - 1) - (0 if superuser else reserved)


def require_connections(db_url: str, processes: int) -> None:
    """Raise TooFewConnections unless the PostgreSQL server of ``db_url`` accepts, now, the connections
    that ``processes`` grading processes hold at once."""
    needed = CONNECTIONS_PER_PROCESS * processes
    limit, free = free_connections(db_url)
    if free < needed:
        raise TooFewConnections(
            f"the gradebook's server accepts {free} more connections now and grading needs {needed} "
            f"({processes} processes x {CONNECTIONS_PER_PROCESS}): raise its max_connections from {limit} to "
            f"{limit + needed - free} or more (README: Large classes), or grade with fewer --jobs.")


@contextmanager
def gradebook_lock(db_url: str, name: str) -> Iterator[None]:
    """Hold the advisory lock ``name`` of the PostgreSQL gradebook at ``db_url`` (waiting for it),
    on a connection of its own. The server keeps it: it holds across machines, and it ends with the
    connection, also when the process holding it dies. With SQLite (one machine, one process
    setting up) there is no lock to take."""
    if not is_server(db_url):
        yield
        return
    engine = create_engine(db_url, poolclass=NullPool, isolation_level="AUTOCOMMIT")
    try:
        with engine.connect() as connection:
            connection.execute(text("SELECT pg_advisory_lock(:key)"), {"key": lock_key(name)})
            try:
                yield
            finally:
                connection.execute(text("SELECT pg_advisory_unlock(:key)"), {"key": lock_key(name)})
    finally:
        engine.dispose()


def submission_lock_name(lab_id: str, student: str) -> str:
    """The name of the lock held while one submission is graded."""
    return f"submission {lab_id} {student}"


def register_class(db_url: str, course_id: str, by_lab: dict[str, list[str]]) -> None:
    """Add the students and submissions of ``by_lab`` (lab id -> students) that the gradebook lacks,
    as nbgrader's autograde would. Call it under the SET_UP lock: then no two processes insert one
    row, every lab being graded has submissions (so nbgrader never deletes its cells again), and
    the gradebook knows the whole class, which ``export`` checks."""
    with Gradebook(db_url, course_id) as gb:
        known = {student.id for student in gb.students}
        for student in sorted({s for students in by_lab.values() for s in students} - known):
            gb.add_student(student)
        for lab_id, students in by_lab.items():
            submitted = {submission.student_id for submission in gb.find_assignment(lab_id).submissions}
            for student in students:
                if student not in submitted:
                    gb.add_submission(lab_id, student)

"""`grade` with a PostgreSQL gradebook checks, before it sets anything up, that the server accepts the
connections that grading opens (two per grading process: README, Large classes), and otherwise refuses
to start with one line that names max_connections and the number it needs: a shard that started anyway
lost submissions to "sorry, too many clients already" part-way (issue 35). The server here is the tests'
(tests/postgres_server.py) with max_connections = 10.
"""

from __future__ import annotations

import psycopg
import pytest
from sqlalchemy.engine import make_url

import shard_runs
from postgres_server import server_fixture
from autograder.catalogues import demo
from autograder.labs import get_lab
from autograder.pipeline.shards import TooFewConnections, free_connections, require_connections

LIMIT = 10
small_server = server_fixture({"max_connections": str(LIMIT)})


def connect(url: str) -> psycopg.Connection:
    parts = make_url(url)
    return psycopg.connect(host=parts.host, port=parts.port, user=parts.username, password=parts.password,
                           dbname=parts.database, autocommit=True)


def test_the_count_of_free_connections_is_what_the_server_then_accepts(small_server):
    """Four connections held by the superuser; a user who is not one gets the slots less the three kept for
    superusers (superuser_reserved_connections): the count is checked against the server by opening them."""
    with connect(small_server) as admin:
        admin.execute("CREATE ROLE grader LOGIN PASSWORD 'grader'")
        admin.execute("GRANT ALL ON DATABASE gradebook TO grader")
    grader_url = make_url(small_server).set(username="grader", password="grader").render_as_string(hide_password=False)
    held = [connect(small_server) for _ in range(4)]
    try:
        assert free_connections(small_server) == (LIMIT, LIMIT - 4)
        assert free_connections(grader_url) == (LIMIT, LIMIT - 4 - 3)
        require_connections(small_server, 3)
        with pytest.raises(TooFewConnections, match=f"needs 8 .*raise its max_connections from {LIMIT} to 12 or more"):
            require_connections(small_server, 4)
        with pytest.raises(TooFewConnections, match=f"accepts 3 more connections now and grading needs 4 "):
            require_connections(grader_url, 2)
        opened = []
        with pytest.raises(psycopg.OperationalError, match="reserved"):
            while len(opened) < LIMIT:
                opened.append(connect(grader_url))
        assert len(opened) == 3
        for connection in opened:
            connection.close()
    finally:
        for connection in held:
            connection.close()


def test_grade_refuses_to_start_when_the_server_would_refuse_its_connections(small_server, tmp_path):
    """`grade --shard 1/1 --jobs 6` on six submissions: 12 connections, where the server takes 10."""
    klass, course = tmp_path / "class", tmp_path / "course"
    demo.write_demo_class([get_lab("train-kf")], klass)
    url = shard_runs.new_database(small_server, "refused")
    run = shard_runs.start_grade(klass, course, url, tmp_path / "grade.log", "--shard", "1/1", "--jobs", "6")
    assert run.process.wait(timeout=600) == 1
    lines = [line for line in run.log.read_text().splitlines() if "max_connections" in line]
    assert lines == [f"grade: the gradebook's server accepts {LIMIT} more connections now and grading needs 12 "
                     f"(6 processes x 2): raise its max_connections from {LIMIT} to 12 or more (README: Large "
                     "classes), or grade with fewer --jobs."], run.log.read_text()[-3000:]
    with connect(url) as connection:  # nothing was set up: nbgrader's tables were never made
        assert connection.execute("SELECT count(*) FROM pg_tables WHERE schemaname = 'public'").fetchone() == (0,)

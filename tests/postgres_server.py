"""A throwaway PostgreSQL server for the tests, from Debian's `postgresql` package.

``running_server()`` initialises a cluster in a new temporary folder, starts ``postgres`` on
127.0.0.1 on a free port (no Unix socket; password authentication with a random password),
creates one database, and yields its SQLAlchemy URL. On exit it stops the server and removes the
folder. It never skips: when the server cannot be found or started it raises ServerUnavailable
with the reason, and the tests that need it fail.

PostgreSQL refuses to run as root. When the tests run as root (as CI does), the server runs as
the unprivileged ``postgres`` account that Debian's package creates (or, if there is none, a
system account ``elk-postgres`` made for it); otherwise it runs as the user running the tests.
"""

from __future__ import annotations

import contextlib
import os
import pwd
import re
import secrets
import shutil
import signal
import socket
import subprocess
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import psycopg
from sqlalchemy.engine import URL

START_TIMEOUT = 30.0  # seconds for the server to accept connections
STOP_TIMEOUT = 20.0
DATABASE = "gradebook"
SUPERUSER = "elk"
INSTALL_HINT = "Install Debian's PostgreSQL server: apt-get install --no-install-recommends postgresql"


class ServerUnavailable(RuntimeError):
    """The PostgreSQL server could not be found or started; the message says why."""


def find_bindir() -> Path:
    """The folder with ``initdb`` and ``postgres``: $POSTGRES_BINDIR, else Debian's newest
    /usr/lib/postgresql/<version>/bin, else the PATH."""
    if os.environ.get("POSTGRES_BINDIR"):
        candidates = [Path(os.environ["POSTGRES_BINDIR"])]
    else:
        versioned = [p for p in Path("/usr/lib/postgresql").glob("*/bin") if re.fullmatch(r"[\d.]+", p.parent.name)]
        candidates = sorted(versioned, key=lambda p: [int(n) for n in p.parent.name.split(".") if n], reverse=True)
        if shutil.which("initdb"):
            candidates.append(Path(shutil.which("initdb")).parent)
    for bindir in candidates:
        if (bindir / "initdb").is_file() and (bindir / "postgres").is_file():
            return bindir
    where = ", ".join(map(str, candidates)) or "/usr/lib/postgresql/*/bin or the PATH"
    raise ServerUnavailable(f"No PostgreSQL server binaries (initdb, postgres) in {where}. {INSTALL_HINT}")


def server_account() -> pwd.struct_passwd | None:
    """The unprivileged account to run the server as when we are root; None when we are not."""
    if os.geteuid() != 0:
        return None
    for name in ("postgres", "elk-postgres"):
        with contextlib.suppress(KeyError):
            return pwd.getpwnam(name)
    nologin = shutil.which("nologin") or "/usr/sbin/nologin"
    subprocess.run(
        ["useradd", "--system", "--no-create-home", "--shell", nologin, "elk-postgres"],
        check=True,
        capture_output=True,
    )
    return pwd.getpwnam("elk-postgres")


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _tail(path: Path, lines: int = 20) -> str:
    text = path.read_text(errors="replace") if path.exists() else ""
    return "\n".join(text.splitlines()[-lines:])


@contextlib.contextmanager
def running_server() -> Iterator[str]:
    """Start a PostgreSQL server on 127.0.0.1 and yield the SQLAlchemy URL of an empty database."""
    bindir = find_bindir()
    account = server_account()
    folder = Path(tempfile.mkdtemp(prefix="elk-postgres-"))
    as_account: dict = {}
    if account is not None:
        as_account = {"user": account.pw_uid, "group": account.pw_gid, "extra_groups": []}
        os.chown(folder, account.pw_uid, account.pw_gid)
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "LC_ALL": "C", "HOME": str(folder)}
    server = None
    try:
        password = secrets.token_urlsafe(24)
        pwfile = folder / "password"
        pwfile.write_text(password + "\n")
        pwfile.chmod(0o600)
        if account is not None:
            os.chown(pwfile, account.pw_uid, account.pw_gid)
        data = folder / "data"
        initdb = subprocess.run(
            [bindir / "initdb", "-D", data, "-U", SUPERUSER, f"--pwfile={pwfile}", "--auth=scram-sha-256",
             "--encoding=UTF8", "--locale=C", "--no-sync"],
            cwd=folder, env=env, capture_output=True, text=True, **as_account,
        )
        if initdb.returncode != 0:
            user = account.pw_name if account else "the current user"
            raise ServerUnavailable(f"initdb failed (as {user}) in {data}:\n{initdb.stdout}{initdb.stderr}")

        log = folder / "server.log"
        for _attempt in range(3):  # another process may take the free port before the server does
            port = free_port()
            with open(log, "w") as log_handle:
                # loopback TCP only (no Unix socket); durability off: the cluster is thrown away
                server = subprocess.Popen(
                    [bindir / "postgres", "-D", data, "-p", str(port), "-c", "listen_addresses=127.0.0.1",
                     "-c", "unix_socket_directories=", "-c", "fsync=off", "-c", "synchronous_commit=off",
                     "-c", "full_page_writes=off"],
                    cwd=folder, env=env, stdin=subprocess.DEVNULL, stdout=log_handle, stderr=subprocess.STDOUT,
                    **as_account,
                )
            if _wait_until_ready(server, port, password, log):
                break
            server.wait()
            server = None
            if "Address already in use" not in log.read_text(errors="replace"):
                break
        if server is None:
            raise ServerUnavailable(f"The PostgreSQL server in {data} exited during start-up:\n{_tail(log)}")

        with psycopg.connect(**_connect_args(port, password, "postgres"), autocommit=True) as connection:
            connection.execute(f'CREATE DATABASE "{DATABASE}"')
        yield URL.create(
            "postgresql+psycopg", SUPERUSER, password, "127.0.0.1", port, DATABASE
        ).render_as_string(hide_password=False)
    finally:
        if server is not None:
            _stop(server)
        shutil.rmtree(folder, ignore_errors=True)


def _connect_args(port: int, password: str, dbname: str) -> dict:
    return {"host": "127.0.0.1", "port": port, "user": SUPERUSER, "password": password, "dbname": dbname,
            "connect_timeout": 5}


def _wait_until_ready(server: subprocess.Popen, port: int, password: str, log: Path) -> bool:
    """True once the server accepts connections; False if it exited. Raises after START_TIMEOUT."""
    deadline = time.monotonic() + START_TIMEOUT
    while time.monotonic() < deadline:
        if server.poll() is not None:
            return False
        try:
            psycopg.connect(**_connect_args(port, password, "postgres")).close()
            return True
        except psycopg.OperationalError:
            time.sleep(0.1)
    _stop(server)
    raise ServerUnavailable(
        f"The PostgreSQL server did not accept connections on 127.0.0.1:{port} within {START_TIMEOUT:g} s:\n"
        + _tail(log)
    )


def _stop(server: subprocess.Popen) -> None:
    """Fast shutdown (SIGINT: roll back open transactions, close connections), then SIGKILL."""
    if server.poll() is None:
        server.send_signal(signal.SIGINT)
        try:
            server.wait(timeout=STOP_TIMEOUT)
        except subprocess.TimeoutExpired:
            server.kill()
            server.wait()

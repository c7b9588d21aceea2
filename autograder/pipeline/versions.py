"""What a set of grades was graded with: Python, the key packages, the kit's commit, and whether the
environment matches the lock file ``environment.lock``.

Grades depend on the environment: NumPy's random streams, SciPy's solvers and nbgrader itself may
change between versions. ``environment.lock`` pins the whole grading environment
(``pip freeze --all --exclude-editable --exclude pip``); a record written beside each grades CSV
says what was used.
"""

from __future__ import annotations

import hashlib
import json
import platform
import re
import subprocess
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path

from packaging.requirements import Requirement

from autograder.kernel import sandbox
from autograder.labs import ROOT
from autograder.pipeline import grading_secret

LOCK = ROOT / "environment.lock"
ENVIRONMENT = ROOT / "environment.txt"
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


def requirements(path: Path = ENVIRONMENT) -> list[Requirement]:
    """The requirements of ``environment.txt`` (the kit itself, ``-e .``, aside)."""
    lines = (line.split("#")[0].strip() for line in path.read_text().splitlines())
    return [Requirement(line) for line in lines if line and not line.startswith("-")]


def _dependencies(name: str, extras: frozenset[str]) -> list[Requirement]:
    """What the installed distribution ``name`` (with ``extras``) requires on this platform."""
    try:
        required = metadata.requires(name) or []
    except metadata.PackageNotFoundError:
        return []
    found = []
    for line in required:
        requirement = Requirement(line)
        if requirement.marker is None or any(requirement.marker.evaluate({"extra": e}) for e in extras | {""}):
            found.append(requirement)
    return found


def needed(path: Path = ENVIRONMENT) -> set[str]:
    """The canonical names of every package that ``environment.txt`` (and the kit's own
    requirements) installs on this platform: their closure over the installed packages' metadata."""
    todo = [(r.name, frozenset(r.extras)) for r in requirements(path)]
    todo += [(r.name, frozenset(r.extras)) for r in _dependencies("estimation-lab-kit", frozenset())]
    found: set[str] = set()
    seen: set[tuple[str, frozenset[str]]] = set()
    while todo:
        name, extras = todo.pop()
        if (_canonical(name), extras) in seen:
            continue
        seen.add((_canonical(name), extras))
        found.add(_canonical(name))
        todo += [(r.name, frozenset(r.extras)) for r in _dependencies(name, extras)]
    return found


def differences_from_lock(path: Path) -> dict[str, dict[str, str | None]]:
    """The locked packages whose installed version differs: name -> {"locked", "installed"}.

    A locked package that is not installed counts only if environment.txt installs it on this
    platform: a lock written where a maintainer's extra tool was installed (jupytext, once), or on
    another platform, must not make every record of an environment installed as README says differ.
    """
    differ = {}
    wanted = needed() if ENVIRONMENT.exists() else None
    for name, locked in read_lock(path).items():
        installed = _installed(name)
        if installed is None and wanted is not None and name not in wanted:
            continue
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


def kernel_course() -> dict[str, str]:
    """The ``course`` package that grading kernels import (this root's, autograder/kernel/manager.py's
    ``course_site``): its folder and a SHA-256 over its Python files' paths and contents."""
    folder = (ROOT / "course").resolve()
    digest = hashlib.sha256()
    for path in sorted(folder.rglob("*.py")):
        digest.update(path.relative_to(folder).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return {"path": str(folder), "sha256": digest.hexdigest()}


def environment() -> dict:
    """The record of the current grading environment."""
    differ = differences_from_lock(LOCK) if LOCK.exists() else None
    return {
        "recorded_at": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "packages": {name: _installed(name) for name in PACKAGES},
        "kit": kit_commit(),
        "kernel_course": kernel_course(),
        "lock_file": LOCK.name,
        "matches_lock": None if differ is None else not differ,
        "differs_from_lock": differ,
    }


def hidden_cases() -> dict[str, str]:
    """What a regrade needs to draw every submission's hidden cases again: the same secret (named by
    its fingerprint, never written here) and the same file (autograder/pipeline/grading_secret.py)."""
    return {"secret_file": str(grading_secret.secret_file()),
            "secret_fingerprint": grading_secret.fingerprint(grading_secret.secret()),
            "seed": "HMAC-SHA256 of the submission's cell types and sources under the secret, first 8 bytes"}


def record(grades_csv: Path) -> Path:
    """Write the environment record beside a grades CSV (``grades.csv`` -> ``grades.versions.json``)."""
    path = Path(grades_csv).with_suffix(".versions.json")
    record = {**environment(), "sandbox": sandbox.status().summary, "hidden_cases": hidden_cases()}
    path.write_text(json.dumps(record, indent=2) + "\n")
    if record["differs_from_lock"]:
        differ = ", ".join(f"{name} {v['installed']} (locked {v['locked']})" if v["installed"] else
                           f"{name} not installed (locked {v['locked']})" for name, v in record["differs_from_lock"].items())
        print(f"Graded in an environment that differs from {LOCK.name}: {differ}. See {path}.")
    return path

"""The grading environment: environment.lock pins every package exactly, within environment.txt's
ranges, and exactly the packages that environment.txt installs; the record written beside a grades
CSV says what the grades were made with, and whether that matches the lock.

That an environment made from environment.lock grades the demo class to the same grades takes a
fresh environment and a graded class (minutes): benchmarks/lock_grades_demo.py does it, for
maintainers before a term and after regenerating the lock.
"""

import json
import platform
import subprocess
from importlib import metadata

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

from autograder import versions
from autograder.labs import ROOT


def requirements() -> list[Requirement]:
    """environment.txt's requirements (the kit itself, `-e .`, aside)."""
    lines = (line.split("#")[0].strip() for line in (ROOT / "environment.txt").read_text().splitlines())
    return [Requirement(line) for line in lines if line and not line.startswith("-")]


def test_the_lock_pins_exact_versions_only():
    lines = [line for line in versions.LOCK.read_text().splitlines() if line and not line.startswith("#")]
    assert lines and all("==" in line and ";" not in line and "@" not in line for line in lines), lines


@pytest.mark.parametrize("requirement", requirements(), ids=str)
def test_the_lock_satisfies_environment_txt(requirement):
    pins = versions.read_lock(versions.LOCK)
    name = versions._canonical(requirement.name)
    assert name in pins, f"{requirement.name} is in environment.txt but not in environment.lock: regenerate the lock"
    assert requirement.specifier.contains(pins[name]), f"environment.lock pins {name}=={pins[name]}, outside {requirement}"


def test_a_package_that_differs_from_the_lock_is_named(tmp_path):
    lock = tmp_path / "environment.lock"
    lock.write_text(f"numpy==0.0.1\nscipy=={metadata.version('scipy')}\nno-such-package==1.0\n")
    assert versions.differences_from_lock(lock) == {
        "numpy": {"locked": "0.0.1", "installed": metadata.version("numpy")},
        "no-such-package": {"locked": "1.0", "installed": None},
    }


def _dependencies(name: str, extras: frozenset[str]) -> list[Requirement]:
    """What the installed distribution ``name`` (with ``extras``) requires on this platform."""
    found = []
    for line in metadata.requires(name) or []:
        requirement = Requirement(line)
        if requirement.marker is None or any(requirement.marker.evaluate({"extra": e}) for e in extras | {""}):
            found.append(requirement)
    return found


def test_the_lock_pins_exactly_what_environment_txt_installs():
    """The closure of environment.txt's requirements (and the kit's own, `-e .`) over the installed
    packages' metadata is the set of packages in the lock: nothing missing, nothing extra (an extra
    package, such as a maintainer's tool, would make every grading record differ from the lock)."""
    todo = [(r.name, frozenset(r.extras)) for r in requirements()]
    todo += [(r.name, frozenset(r.extras)) for r in _dependencies("estimation-lab-kit", frozenset())]
    needed: set[str] = set()
    seen: set[tuple[str, frozenset[str]]] = set()
    while todo:
        name, extras = todo.pop()
        if (canonicalize_name(name), extras) in seen:
            continue
        seen.add((canonicalize_name(name), extras))
        needed.add(canonicalize_name(name))
        todo += [(r.name, frozenset(r.extras)) for r in _dependencies(name, extras)]
    locked = set(versions.read_lock(versions.LOCK))
    assert locked - needed == set(), f"environment.lock pins packages that environment.txt does not install: {locked - needed}"
    assert needed - locked <= {"pip", "setuptools"}, f"environment.lock lacks {needed - locked - {'pip', 'setuptools'}}"


def test_the_record_says_whether_the_environment_matches_the_lock(tmp_path, monkeypatch):
    """Against locks written for the purpose: one that pins what is installed, one that differs."""
    installed = {name: metadata.version(name) for name in ("numpy", "scipy", "nbgrader")}
    same, differs = tmp_path / "same.lock", tmp_path / "differs.lock"
    same.write_text("".join(f"{name}=={version}\n" for name, version in installed.items()))
    differs.write_text(f"numpy==0.0.1\nscipy=={installed['scipy']}\nno-such-package==1.0\n")
    for lock, matches, differences in (
        (same, True, {}),
        (differs, False, {"numpy": {"locked": "0.0.1", "installed": installed["numpy"]},
                          "no-such-package": {"locked": "1.0", "installed": None}}),
        (tmp_path / "missing.lock", None, None),
    ):
        monkeypatch.setattr(versions, "LOCK", lock)
        record = json.loads(versions.record(tmp_path / "grades.csv").read_text())
        assert (record["matches_lock"], record["differs_from_lock"]) == (matches, differences), lock.name


def test_the_record_says_what_the_grades_were_made_with(tmp_path):
    path = versions.record(tmp_path / "grades.csv")
    assert path == tmp_path / "grades.versions.json"
    record = json.loads(path.read_text())
    assert record["python"] == platform.python_version()
    for name in ("numpy", "scipy", "nbgrader"):
        assert record["packages"][name] == metadata.version(name)
    head = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True, text=True)
    assert record["kit"]["commit"] == (head.stdout.strip() if head.returncode == 0 else None)

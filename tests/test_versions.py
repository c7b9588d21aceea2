"""The grading environment: environment.lock pins every package exactly, within environment.txt's
ranges, and the record written beside a grades CSV says what the grades were made with."""

import json
import platform
import subprocess
from importlib import metadata

import pytest
from packaging.requirements import Requirement

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


def test_the_record_says_what_the_grades_were_made_with(tmp_path):
    path = versions.record(tmp_path / "grades.csv")
    assert path == tmp_path / "grades.versions.json"
    record = json.loads(path.read_text())
    assert record["python"] == platform.python_version()
    for name in ("numpy", "scipy", "nbgrader"):
        assert record["packages"][name] == metadata.version(name)
    head = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True, text=True)
    assert record["kit"]["commit"] == (head.stdout.strip() if head.returncode == 0 else None)
    assert record["matches_lock"] == (not versions.differences_from_lock(versions.LOCK))

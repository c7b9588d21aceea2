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

from autograder.pipeline import versions
from autograder.labs import ROOT


requirements = versions.requirements


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
    # no-such-package is not installed, and environment.txt does not install it: no difference
    assert versions.differences_from_lock(lock) == {
        "numpy": {"locked": "0.0.1", "installed": metadata.version("numpy")},
    }


def test_the_lock_pins_exactly_what_environment_txt_installs():
    """The closure of environment.txt's requirements (and the kit's own, `-e .`) over the installed
    packages' metadata is the set of packages in the lock: nothing missing, nothing extra (an extra
    package, such as a maintainer's tool, would make every grading record differ from the lock)."""
    needed = versions.needed()
    assert {"numpy", "nbgrader", "jupyterlab", "tqdm", "traitlets"} <= needed  # direct and indirect requirements
    locked = set(versions.read_lock(versions.LOCK))
    assert locked - needed == set(), f"environment.lock pins packages that environment.txt does not install: {locked - needed}"
    assert needed - locked <= {"pip", "setuptools"}, f"environment.lock lacks {needed - locked - {'pip', 'setuptools'}}"


def test_a_locked_package_that_environment_txt_does_not_install_is_no_difference(tmp_path, monkeypatch, capsys):
    """The lock once pinned jupytext, which a maintainer had installed and environment.txt did not then:
    every environment installed as README says warned 'differs from environment.lock: jupytext None'.
    A locked package that is absent counts only if environment.txt installs it here."""
    tool = "a-maintainers-own-tool"
    with pytest.raises(metadata.PackageNotFoundError):
        metadata.version(tool)
    assert tool not in versions.needed()
    lock = tmp_path / "environment.lock"
    lock.write_text(versions.LOCK.read_text() + f"{tool}==1.0\n")
    # an environment installed from the lock, whatever the newest releases in environment.txt's ranges are today
    installed = {versions._canonical(name): version for name, version in versions.read_lock(versions.LOCK).items()}
    monkeypatch.setattr(versions, "_installed", lambda name: installed.get(versions._canonical(name)))
    monkeypatch.setattr(versions, "LOCK", lock)
    versions.record(tmp_path / "grades.csv")
    record = json.loads((tmp_path / "grades.versions.json").read_text())
    assert (record["matches_lock"], record["differs_from_lock"]) == (True, {})
    assert "differs" not in capsys.readouterr().out
    # a package that environment.txt installs, missing, still counts, and the warning says so in words
    installed["numpy"] = None
    versions.record(tmp_path / "grades.csv")
    out = capsys.readouterr().out
    assert f"numpy not installed (locked {versions.read_lock(lock)['numpy']})" in out, out
    assert "None" not in out


def test_the_record_says_whether_the_environment_matches_the_lock(tmp_path, monkeypatch):
    """Against locks written for the purpose: one that pins what is installed, one that differs."""
    installed = {name: metadata.version(name) for name in ("numpy", "scipy", "nbgrader")}
    same, differs = tmp_path / "same.lock", tmp_path / "differs.lock"
    same.write_text("".join(f"{name}=={version}\n" for name, version in installed.items()))
    differs.write_text(f"numpy==0.0.1\nscipy=={installed['scipy']}\nno-such-package==1.0\n")
    for lock, matches, differences in (
        (same, True, {}),
        (differs, False, {"numpy": {"locked": "0.0.1", "installed": installed["numpy"]}}),
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

"""A test that needs something environment.txt does not install (tests/machine_needs.py) says so where it
is missing, and CI cannot lose it: skipped with the command that adds it on a user's machine, failed
under KIT_RUN_EVERY_TEST=1, which .ci/run sets before README's test command."""

from __future__ import annotations

import os
import re
import subprocess
import sys

from autograder.labs import ROOT
from machine_needs import NEEDS, RUN_EVERY_TEST

BROWSER_TESTS = ["tests/test_student_browser.py", "tests/test_hostile_pages.py"]


def _pytest(*args: str, **env: str) -> subprocess.CompletedProcess:
    environment = {k: v for k, v in os.environ.items() if k != RUN_EVERY_TEST and not k.startswith("PYTEST_XDIST")}
    return subprocess.run([sys.executable, "-m", "pytest", "-p", "no:xdist", "-p", "no:randomly", *args],
                          cwd=ROOT, env=environment | env, capture_output=True, text=True, timeout=600)


def test_ci_installs_every_need_and_runs_every_test_with_readmes_command():
    script = (ROOT / ".ci" / "run").read_text()
    readme_command = re.search(r"^\.venv/bin/python -m pytest .*$", (ROOT / "README.md").read_text(), re.M).group(0)
    export = script.index(f"export {RUN_EVERY_TEST}=1")
    assert export < script.index(readme_command), "KIT_RUN_EVERY_TEST must be set before the test command"
    assert "apt-get install" in script and "chromium" in script.split(readme_command)[0]
    assert "npm install --global --silent configurable-http-proxy" in script.split(readme_command)[0]
    assert "apt-get install -y -qq --no-install-recommends slurm-wlm munge" in script.split(readme_command)[0]
    assert set(NEEDS) == {"chromium", "configurable-http-proxy", "slurm", "root"}, (
        "a new need must be installed by .ci/run (and listed in README)")


def test_without_chromium_the_browser_tests_are_skipped_naming_it_and_the_command_that_adds_it():
    run = _pytest(*BROWSER_TESTS, "-q", CHROMIUM="/nonexistent/chromium")
    assert run.returncode == 0, run.stdout[-3000:]
    section = run.stdout.split("tests that did not run on this machine", 1)[1]
    assert "apt-get install --no-install-recommends chromium" in section, section
    counted = {m.group(2): int(m.group(1)) for m in re.finditer(r"^  (\d+) tests? in (\S+)$", section, re.M)}
    assert counted["tests/test_student_browser.py"] >= 4 and counted["tests/test_hostile_pages.py"] == 2, section
    assert re.search(r"\d+ skipped", run.stdout.splitlines()[-1]) and "failed" not in run.stdout.splitlines()[-1]


def test_under_ci_a_missing_chromium_fails_the_browser_tests_before_they_start_anything():
    run = _pytest("tests/test_student_browser.py", "-q", CHROMIUM="/nonexistent/chromium", **{RUN_EVERY_TEST: "1"})
    assert run.returncode == 1, run.stdout[-3000:]
    assert "Cannot run here, and CI runs every test" in run.stdout and "skipped" not in run.stdout.splitlines()[-1]


def test_without_slurm_its_test_is_skipped_naming_it_and_under_ci_it_fails():
    """No Slurm on the PATH (its programs are looked up there, as on a user's machine without the packages)."""
    path = {"PATH": "/nonexistent"}
    run = _pytest("tests/test_slurm.py", "-q", **path)
    assert run.returncode == 0, run.stdout[-3000:]
    section = run.stdout.split("tests that did not run on this machine", 1)[1]
    assert "apt-get install --no-install-recommends slurm-wlm munge" in section and "tests/test_slurm.py" in section
    assert "1 skipped" in run.stdout.splitlines()[-1]
    run = _pytest("tests/test_slurm.py", "-q", **path, **{RUN_EVERY_TEST: "1"})
    assert run.returncode == 1 and "Cannot run here, and CI runs every test" in run.stdout, run.stdout[-3000:]

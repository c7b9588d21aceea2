"""Tests that need something environment.txt does not install, and what happens where it is missing.

README's test command must pass on a machine that has only what README's first command installed
(Python and environment.txt). A test that needs more is marked ``@pytest.mark.needs("<name>")``
with a name from ``NEEDS``. Where that thing is missing:

- on a user's machine, the test is skipped with a reason that names what is missing and the one
  command that adds it, and the run ends with a section listing every such test (``summary_lines``):
  it never passes silently;
- where ``KIT_RUN_EVERY_TEST=1`` is set (``.ci/run`` sets it), the test fails at once, before its
  fixtures, with the same words: CI cannot lose a test to a missing package unnoticed
  (tests/test_machine_needs.py checks both, and that ``.ci/run`` sets the variable).
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pytest

import slurm_cluster

RUN_EVERY_TEST = "KIT_RUN_EVERY_TEST"
"""Set to 1 (``.ci/run`` does): a test whose need is missing fails instead of being skipped."""
SKIPPED = "Not run on this machine: "
"""How every skip reason of a missing need begins (the summary finds them by it)."""


def _chromium_present() -> bool:
    """$CHROMIUM, if set, names an existing file; else ``chromium`` is on the PATH."""
    named = os.environ.get("CHROMIUM")
    return Path(named).is_file() if named else shutil.which("chromium") is not None


@dataclass(frozen=True)
class Need:
    """Something outside environment.txt that some tests use."""

    what: str
    """In words, for the message."""
    install: str
    """The one command that adds it (Debian), with any other way to point the tests at it."""
    present: Callable[[], bool]


NEEDS: dict[str, Need] = {
    "chromium": Need(
        "Debian's Chromium, the real browser that Playwright drives (Playwright's own download is not used)",
        "`sudo apt-get install --no-install-recommends chromium` (or set CHROMIUM to a Chromium's path)",
        _chromium_present),
    "configurable-http-proxy": Need(
        "JupyterHub's proxy, configurable-http-proxy (Node.js), for the hub recipe's test",
        "`sudo apt-get install --no-install-recommends nodejs npm && sudo npm install -g configurable-http-proxy`",
        lambda: shutil.which("configurable-http-proxy") is not None),
    "slurm": Need(
        "a single-node Slurm that the test starts on 127.0.0.1 (Debian's slurm-wlm, 22.05, and munge), for README's "
        "Slurm array",
        "`sudo apt-get install --no-install-recommends slurm-wlm munge`",
        slurm_cluster.present),
    "root": Need(
        "to run as root, since the hub recipe's test adds local users and the hub starts each user's server as that "
        "user (CI runs as root)",
        "`sudo`, in a machine or container where adding users is fine",
        lambda: os.geteuid() == 0),
}


def message(name: str) -> str:
    """What is missing and how to add it."""
    need = NEEDS[name]
    return f"{SKIPPED}it needs {need.what}. Add it with {need.install}, then run the tests again."


def missing_needs(item: pytest.Item) -> list[str]:
    """The names of ``item``'s needs that this machine does not have."""
    names = [name for marker in item.iter_markers("needs") for name in marker.args]
    unknown = sorted(set(names) - NEEDS.keys())
    if unknown:
        raise pytest.UsageError(f"{item.nodeid} needs {', '.join(unknown)}, which tests/machine_needs.py does not know")
    return [name for name in dict.fromkeys(names) if not NEEDS[name].present()]


def run_every_test() -> bool:
    return os.environ.get(RUN_EVERY_TEST) == "1"


def summary_lines(skipped: list[pytest.TestReport]) -> list[str]:
    """For each missing need among the skipped tests' reports: what it is and how to add it, then each
    test file with how many of its tests did not run."""
    by_reason: dict[str, dict[str, int]] = {}
    for report in skipped:
        if isinstance(report.longrepr, tuple) and SKIPPED in report.longrepr[2]:
            reason = report.longrepr[2][report.longrepr[2].index(SKIPPED) + len(SKIPPED):]
            files = by_reason.setdefault(reason, {})
            files[report.nodeid.split("::")[0]] = files.get(report.nodeid.split("::")[0], 0) + 1
    lines = []
    for reason, files in sorted(by_reason.items()):
        lines.append(f"These tests did not run. Each {reason.removeprefix('it ')}")
        lines += [f"  {n} test{'s' if n > 1 else ''} in {path}" for path, n in sorted(files.items())]
    return lines

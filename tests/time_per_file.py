"""Where the test run's time went, per test file and per xdist worker, for the end of the run's report.

With ``pytest -n 2 --dist loadfile`` a file runs whole on one worker, so the run lasts as long as
its busiest worker. ``--durations`` names slow tests; this names slow files and shows whether the
two workers finished together or one waited on the other's last file, which is what a maintainer
needs to know to bring CI's time down (split a slow file, or move work between files).
"""

from __future__ import annotations

import json
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path

import pytest


@dataclass
class FileTime:
    """One test file's share of the run: its busy seconds and when (epoch seconds) it started and ended."""

    worker: str
    seconds: float = 0.0
    start: float = float("inf")
    stop: float = 0.0


def worker_of(report: pytest.TestReport) -> str:
    """The xdist worker that ran ``report``'s test (``gw0``, ...), or ``main`` without xdist."""
    node = getattr(report, "node", None)
    return node.gateway.id if node is not None else "main"


def file_times(reports: list[pytest.TestReport]) -> dict[str, FileTime]:
    """The time of each test file: path -> FileTime, from every set-up, call and tear-down report."""
    files: dict[str, FileTime] = {}
    for report in reports:
        path = report.nodeid.split("::")[0]
        time = files.setdefault(path, FileTime(worker_of(report)))
        time.seconds += report.duration
        time.start, time.stop = min(time.start, report.start), max(time.stop, report.stop)
    return files


def summary_lines(files: dict[str, FileTime], slowest: int = 15) -> list[str]:
    """Each worker's busy and finishing time (minutes from the run's first test), then the ``slowest``
    files with their worker and the minute each started."""
    if not files:
        return []
    begin = min(time.start for time in files.values())
    busy, end = defaultdict(float), defaultdict(float)
    for time in files.values():
        busy[time.worker] += time.seconds
        end[time.worker] = max(end[time.worker], time.stop - begin)
    lines = [f"{worker}: busy {busy[worker] / 60:.1f} min, finished at {end[worker] / 60:.1f} min"
             for worker in sorted(busy)]
    lines.append(f"{'seconds':>8} {'worker':>6} {'started':>8}  file")
    for path, time in sorted(files.items(), key=lambda item: -item[1].seconds)[:slowest]:
        lines.append(f"{time.seconds:8.0f} {time.worker:>6} {(time.start - begin) / 60:7.1f}m  {path}")
    return lines


SECONDS_FILE = Path(__file__).with_name("file_seconds.json")
"""Each test file's busy seconds in a whole run of README's test command, which the run's order
follows (``slowest_first``); ``--file-seconds`` writes it again."""
UNKNOWN_SECONDS = 60.0
"""The cost assumed for a file that the record does not name yet (a new one): early, not last."""


def slowest_first(items: list[pytest.Item], seconds: dict[str, float]) -> None:
    """Order ``items`` so that the files that took longest come first, each file's tests in their order.

    With ``-n 2 --dist loadfile`` xdist hands whole files to the workers in this order (its own
    reorder, by the number of tests, is turned off), so the longest files start at once and the
    short ones fill in at the end: both workers finish close together."""
    order = {path: i for i, path in enumerate(dict.fromkeys(item.nodeid.split("::")[0] for item in items))}
    items.sort(key=lambda item: (-seconds.get(item.nodeid.split("::")[0], UNKNOWN_SECONDS),
                                 order[item.nodeid.split("::")[0]]))


def write_seconds(path: Path, files: dict[str, FileTime]) -> None:
    """Record each file's busy seconds (rounded), for ``slowest_first`` in later runs."""
    path.write_text(json.dumps({name: round(time.seconds) for name, time in sorted(files.items())}, indent=1) + "\n")


def write_summary(terminalreporter: pytest.TerminalReporter) -> None:
    """Write the summary under its own heading (nothing if no test ran); with ``--file-seconds PATH``,
    record each file's seconds there."""
    reports = [report for reports in terminalreporter.stats.values() for report in reports
               if isinstance(report, pytest.TestReport) and report.duration]
    files = file_times(reports)
    record = terminalreporter.config.getoption("file_seconds", None)
    if record and files:
        write_seconds(Path(record), files)
    lines = summary_lines(files)
    if lines:
        terminalreporter.write_sep("=", "time per test file and worker")
        for line in lines:
            terminalreporter.write_line(line)

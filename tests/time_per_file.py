"""Where the test run's time went, per test file and per xdist worker, for the end of the run's report.

With ``pytest -n 2 --dist loadfile`` a file runs whole on one worker, so the run lasts as long as
its busiest worker. ``--durations`` names slow tests; this names slow files and shows whether the
two workers finished together or one waited on the other's last file, which is what a maintainer
needs to know to bring CI's time down (split a slow file, or move work between files).
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass

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


def write_summary(terminalreporter: pytest.TerminalReporter) -> None:
    """Write the summary under its own heading (nothing if no test ran)."""
    reports = [report for reports in terminalreporter.stats.values() for report in reports
               if isinstance(report, pytest.TestReport) and report.duration]
    lines = summary_lines(file_times(reports))
    if lines:
        terminalreporter.write_sep("=", "time per test file and worker")
        for line in lines:
            terminalreporter.write_line(line)

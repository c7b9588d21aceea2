"""The end-of-run summary of time per test file and worker (tests/time_per_file.py)."""

from types import SimpleNamespace

import pytest

from time_per_file import file_times, summary_lines


def _report(nodeid: str, worker: str | None, start: float, stop: float) -> pytest.TestReport:
    report = pytest.TestReport(nodeid, ("f", 0, "t"), {}, "passed", None, "call", duration=stop - start,
                               start=start, stop=stop)
    if worker is not None:
        report.node = SimpleNamespace(gateway=SimpleNamespace(id=worker))
    return report


def test_each_file_is_timed_on_its_worker_and_the_slowest_comes_first() -> None:
    reports = [_report("tests/test_a.py::one", "gw0", 1000, 1060), _report("tests/test_a.py::two", "gw0", 1060, 1090),
               _report("tests/test_b.py::one", "gw1", 1000, 1030), _report("tests/test_c.py::one", "gw1", 1030, 1270)]
    files = file_times(reports)
    assert (files["tests/test_a.py"].seconds, files["tests/test_a.py"].worker) == (90, "gw0")
    assert (files["tests/test_a.py"].start, files["tests/test_a.py"].stop) == (1000, 1090)
    lines = summary_lines(files, slowest=2)
    assert lines[:2] == ["gw0: busy 1.5 min, finished at 1.5 min", "gw1: busy 4.5 min, finished at 4.5 min"]
    assert [line.split()[-1] for line in lines[3:]] == ["tests/test_c.py", "tests/test_a.py"]
    assert lines[3].split()[:3] == ["240", "gw1", "0.5m"]


def test_without_xdist_the_worker_is_main_and_no_test_means_no_summary() -> None:
    assert file_times([_report("tests/test_a.py::one", None, 0, 1)])["tests/test_a.py"].worker == "main"
    assert summary_lines({}) == []

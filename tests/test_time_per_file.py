"""The end-of-run summary of time per test file and worker (tests/time_per_file.py)."""

import json
from types import SimpleNamespace

import pytest

from time_per_file import file_times, slowest_first, summary_lines, write_seconds


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


def test_the_slowest_files_run_first_and_a_new_file_is_not_left_for_last(tmp_path) -> None:
    items = [SimpleNamespace(nodeid=n) for n in ("tests/test_a.py::one", "tests/test_a.py::two", "tests/test_b.py::one",
                                                 "source/lab/lab.ipynb::Cell 0", "tests/test_new.py::one")]
    slowest_first(items, {"tests/test_a.py": 5, "tests/test_b.py": 300, "source/lab/lab.ipynb": 90})
    assert [i.nodeid for i in items] == ["tests/test_b.py::one", "source/lab/lab.ipynb::Cell 0", "tests/test_new.py::one",
                                         "tests/test_a.py::one", "tests/test_a.py::two"]
    reports = [_report("tests/test_a.py::one", "gw0", 0, 2.4), _report("tests/test_a.py::two", "gw0", 2.4, 3.0)]
    write_seconds(tmp_path / "seconds.json", file_times(reports))
    assert json.loads((tmp_path / "seconds.json").read_text()) == {"tests/test_a.py": 3}


def test_xdist_hands_out_the_files_in_our_order(pytestconfig) -> None:
    """xdist's own reorder (by number of tests) is off, else slowest_first would change nothing."""
    assert getattr(pytestconfig.option, "loadscopereorder", False) is False

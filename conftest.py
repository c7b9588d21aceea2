"""Shared test set-up (at the root, so that `pytest source/<lab>` alone gets it too).

The solved notebooks (nbval) and the grading kernels run hidden tests that import `solutions` and
`autograder`, which are not installed. Kernels inherit PYTHONPATH, so put the course root on it,
as nbgrader_config.py does for grading.

`pytest --lab <lab>` runs one lab's tests alone: every other test is deselected, and the fixtures
that grade a class grade that lab only (tests/over_labs.py, ``chosen``). A test concerns the labs
it is parametrized with (``lab``), the labs its ``labs`` marker names (``over_labs.about``), the lab
of the notebook it runs (nbval, ``source/<lab>/``) or of its file (``tests/test_<module>_reference.py``);
any other test is one of the kit's own and runs only without --lab.
"""

import os
import re

import pytest

from autograder.labs import ROOT, Lab, all_labs

os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH")) if p)
# Every test run grades with the same grading secret, so that each submission gets the same hidden
# cases in every run (autograder/pipeline/grading_secret.py); tests/test_case_seeds.py tries other seeds.
os.environ["KIT_GRADING_SECRET_FILE"] = str(ROOT / "tests" / "grading-secret-for-tests")

REFERENCE_TESTS = re.compile(r"test_(\w+)_reference\.py")
"""A lab's own test file, ``tests/test_<module>_reference.py``."""


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--lab", action="append", default=[], metavar="LAB", type=lambda name: name.replace("_", "-"),
                     help="run only the tests of this lab (its id, e.g. train-kf; repeat for several): the others "
                          "are deselected, and the grading fixtures grade this lab only")
    parser.addoption("--file-seconds", metavar="PATH", default=None,
                     help="write each test file's busy seconds to PATH as JSON, as tests/file_seconds.json records them "
                          "for the run's order (tests/time_per_file.py)")


def pytest_configure(config: pytest.Config) -> None:
    if hasattr(config.option, "loadscopereorder"):
        # xdist would hand out files by their number of tests; tests/conftest.py orders them slowest first
        config.option.loadscopereorder = False
    config.addinivalue_line("markers", "labs(*lab_ids): the labs a test concerns, for --lab (none: a test of the kit itself)")
    unknown = sorted(set(config.getoption("lab")) - {lab.id for lab in all_labs()})
    if unknown:
        raise pytest.UsageError(f"--lab {', '.join(unknown)}: no such lab. The labs are: "
                                f"{', '.join(lab.id for lab in all_labs())}.")


def labs_of(item: pytest.Item) -> set[str]:
    """The ids of the labs a test concerns; none for a test of the kit's own machinery."""
    lab = getattr(item, "callspec", None) and item.callspec.params.get("lab")
    if isinstance(lab, Lab):
        return {lab.id}
    marker = item.get_closest_marker("labs")
    if marker is not None:
        return set(marker.args)
    if item.path.is_relative_to(ROOT / "source"):
        return {item.path.relative_to(ROOT / "source").parts[0]}
    reference = REFERENCE_TESTS.fullmatch(item.path.name)
    return {reference.group(1).replace("_", "-")} if reference else set()


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """With --lab: deselect every test that concerns none of the chosen labs."""
    wanted = set(config.getoption("lab"))
    if not wanted:
        return
    kept = [item for item in items if labs_of(item) & wanted]
    dropped = [item for item in items if not labs_of(item) & wanted]
    if dropped:
        config.hook.pytest_deselected(items=dropped)
        items[:] = kept

"""Runs every test that draws random numbers on seed 0 and 20 other seeds (see tests/random_draws.py)."""

import json

import pytest

import machine_needs
from random_draws import SEEDS
from time_per_file import SECONDS_FILE, slowest_first, write_summary


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "random_draws(false_fail, why, own_seeds, fixed_seed, scope): the test draws random "
        "numbers; it states its false-fail probability, and a `seed` argument runs it on every seed in "
        "tests/random_draws.py's SEEDS")
    config.addinivalue_line(
        "markers", "needs(*names): the test needs something environment.txt does not install (tests/machine_needs.py): "
        "skipped, saying how to add it, where it is missing; failed there under KIT_RUN_EVERY_TEST=1 (CI)")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Run the slowest files first (tests/time_per_file.py); skip, saying what to install, a test whose need
    this machine lacks (tests/machine_needs.py), unless every test must run (CI): then it fails in its set-up."""
    slowest_first(items, json.loads(SECONDS_FILE.read_text()) if SECONDS_FILE.exists() else {})
    if machine_needs.run_every_test():
        return
    for item in items:
        for name in machine_needs.missing_needs(item):
            item.add_marker(pytest.mark.skip(reason=machine_needs.message(name)))


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item: pytest.Item) -> None:
    """Under KIT_RUN_EVERY_TEST=1, a missing need fails the test before any fixture is set up."""
    if machine_needs.run_every_test():
        for name in machine_needs.missing_needs(item):
            pytest.fail(machine_needs.message(name).replace(machine_needs.SKIPPED, "Cannot run here, and CI runs every test: "),
                        pytrace=False)


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    """Parametrise ``seed`` over SEEDS for a test marked random_draws; refuse an unmarked ``seed``."""
    if "seed" not in metafunc.fixturenames:
        return
    marker = metafunc.definition.get_closest_marker("random_draws")
    if marker is None:
        raise pytest.UsageError(f"{metafunc.definition.nodeid} takes `seed` but states no false-fail "
                                "probability: decorate it with @random_draws(...) (tests/random_draws.py)")
    metafunc.parametrize("seed", SEEDS, ids=[f"seed{s}" for s in SEEDS], scope=marker.kwargs["scope"])


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    """Say where the browser test saved its screenshots (tests/test_student_browser.py records the
    folder as the property ``screenshots``), also when it ran in an xdist worker and passed; then
    the time per test file and worker (tests/time_per_file.py)."""
    folders = sorted({value for reports in terminalreporter.stats.values() for report in reports
                      for name, value in getattr(report, "user_properties", ()) if name == "screenshots"})
    for folder in folders:
        terminalreporter.write_line(f"Screenshots of the browser test: {folder}")
    not_run = machine_needs.summary_lines(terminalreporter.stats.get("skipped", []))
    if not_run:
        terminalreporter.write_sep("=", "tests that did not run on this machine")
        for line in not_run:
            terminalreporter.write_line(line)
    write_summary(terminalreporter)

"""A student's session in JupyterLab, in a real browser (headless Debian Chromium, via Playwright).

From a fresh student bundle (tests/student_jupyterlab.py), the tests open train-kf's release
notebook, run all cells and read the first NotWrittenYet message; type the model answer of one
blank, then a catalogued mistake, and read the visible check's message each time; press nbgrader's
Validate and read its dialog; and look for instructor tools. Every wait is on the page's own state
(Playwright's auto-waiting locators and ``expect``), never a fixed sleep. A screenshot of each
step goes to the folder printed at the start (``student-jupyterlab-screenshots`` under pytest's
temporary folder), also when the step fails.

The tests share one JupyterLab and one page, in file order; each one sets up the state it reads,
so that any one of them also runs alone.
"""

from __future__ import annotations

import contextlib
import re
from collections.abc import Iterator
from pathlib import Path

import nbformat
import pytest
from playwright.sync_api import Locator, Page, expect

from autograder import cells
from autograder.labs import get_lab
from autograder.catalogues.mistakes import catalogue
from student_jupyterlab import JupyterLab, chromium, running_jupyterlab

LAB = get_lab("train-kf")  # the smallest lab: its first blank's check runs in well under a second
BLANK = "gain_information_form"  # the first blank of train-kf
MISTAKE = "B-not-inverted"  # a catalogued mistake in it that the visible check catches
NOTEBOOK = f"release/{LAB.id}/{LAB.notebook_name}"
WAIT_MS = 120_000  # generous: a kernel start and a run on a loaded 2-core CI machine
INSTRUCTOR_TOOLS = ("Formgrader", "Create Assignment", "Assignment List")
expect.set_options(timeout=WAIT_MS)  # every wait on the page's state (Playwright's default is 5 s)
pytestmark = pytest.mark.needs("chromium")


@pytest.fixture(scope="module")
def screenshots(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("student-jupyterlab-screenshots", numbered=False)
    print(f"Screenshots of the browser test: {folder}")
    return folder


@pytest.fixture(autouse=True)
def _screenshots_in_the_summary(record_property, screenshots: Path) -> None:
    """Record the folder for the terminal summary (tests/conftest.py), which prints it under xdist too."""
    record_property("screenshots", str(screenshots))


@pytest.fixture(scope="module")
def jupyterlab(tmp_path_factory: pytest.TempPathFactory) -> Iterator[JupyterLab]:
    with running_jupyterlab(tmp_path_factory.mktemp("student-jupyterlab")) as server:
        yield server


@pytest.fixture(scope="module")
def page(jupyterlab: JupyterLab, screenshots: Path) -> Iterator[Page]:
    """The release notebook open in JupyterLab, its kernel idle, every cell run once."""
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.set_default_timeout(WAIT_MS)
        with step(page, screenshots, "01-notebook-opened"):
            page.goto(jupyterlab.lab_url(NOTEBOOK))
            expect(page.locator(".jp-NotebookPanel")).to_be_visible()
            # JupyterLab attaches the cells in batches while the page is idle; wait for them all.
            expect(all_cells(page)).to_have_count(len(release_notebook().cells))
            expect(kernel_status(page)).to_have_text(re.compile("Idle"))
        with step(page, screenshots, "02-run-all-not-written-yet"):
            page.get_by_role("menuitem", name="Run", exact=True).click()
            page.get_by_role("menuitem", name="Run All Cells", exact=True).click()
            first_check = cell(page, index_of(f"check_{BLANK}"))
            expect(first_check.locator(".jp-OutputArea-output")).to_contain_text("NotWrittenYet")
            expect(kernel_status(page)).to_have_text(re.compile("Idle"))
            first_check.scroll_into_view_if_needed()
        yield page


@contextlib.contextmanager
def step(page: Page, folder: Path, name: str) -> Iterator[None]:
    """Screenshot the page after a step, whether its assertions pass or fail."""
    try:
        yield
    finally:
        page.screenshot(path=folder / f"{name}.png")


def release_notebook() -> nbformat.NotebookNode:
    return cells.read(LAB.release_notebook)


def index_of(grade_id: str) -> int:
    """The position of the cell with this nbgrader grade_id in the release notebook."""
    [index] = [i for i, c in enumerate(release_notebook().cells) if cells.meta(c).get("grade_id") == grade_id]
    return index


def all_cells(page: Page) -> Locator:
    return page.locator(".jp-NotebookPanel .jp-Notebook .jp-Cell")


def cell(page: Page, index: int) -> Locator:
    return all_cells(page).nth(index)


def kernel_status(page: Page) -> Locator:
    """The status bar's kernel item, "Python 3 (ipykernel) | Idle" once the kernel is ready."""
    return page.locator(".jp-StatusBar-Widget").filter(has_text="Python 3")


def model_answer() -> str:
    """The blank's model answer in the source notebook (the code of solutions/train_kf/reference.py: a test
    compares their syntax trees)."""
    return cells.model_answers(cells.read(LAB.source_notebook))[BLANK]


def mistaken_answer() -> str:
    [mistake] = [m for m in catalogue(LAB) if m.blank == BLANK and m.slug == MISTAKE]
    return mistake.apply(model_answer())


def write_blank_and_run(page: Page, code: str) -> Locator:
    """Replace the blank's code with ``code`` as a student pastes it, run the blank and its check
    cell (Shift+Enter twice), and return the check cell once it has run."""
    answer, check = cell(page, index_of(BLANK)), cell(page, index_of(f"check_{BLANK}"))
    expect(answer).to_contain_text(f"def {BLANK}(")
    ran_before = check.locator(".jp-InputPrompt").inner_text()
    editor = answer.locator(".cm-content")
    editor.click()
    page.keyboard.press("ControlOrMeta+a")
    page.keyboard.insert_text(code)  # as pasted: the editor's auto-indentation and brackets stay out
    assert editor.inner_text() == code, f"the blank holds\n{editor.inner_text()}\ninstead of\n{code}"
    page.keyboard.press("Shift+Enter")
    expect(check).to_have_class(re.compile(r"\bjp-mod-selected\b"))
    page.keyboard.press("Shift+Enter")
    # Done once the check's prompt shows a new execution count ("[*]" while it runs).
    expect(check.locator(".jp-InputPrompt")).not_to_have_text(ran_before)
    expect(check.locator(".jp-InputPrompt")).to_have_text(re.compile(r"\[\d+\]"))
    answer.evaluate("node => node.scrollIntoView({block: 'start'})")  # the screenshot shows both cells
    return check


def test_run_all_stops_at_the_first_blank_with_not_written_yet(page: Page) -> None:
    """Run All runs the set-up cells, then stops at the first check with NotWrittenYet."""
    outputs = all_cells(page).evaluate_all(
        "cells => cells.map(c => c.querySelector('.jp-OutputArea')?.textContent ?? '')")
    assert len(outputs) == len(release_notebook().cells)
    stopped = [i for i, text in enumerate(outputs) if "NotWrittenYet" in text]
    assert stopped == [index_of(f"check_{BLANK}")], (
        f"NotWrittenYet should show in the check of {BLANK} only, where Run All stops; it shows in cells {stopped}")
    message = outputs[stopped[0]]
    assert BLANK in message, f"The NotWrittenYet message does not name {BLANK}: {message}"
    setup = cell(page, index_of("setup"))
    expect(setup.locator(".jp-InputPrompt")).to_have_text(re.compile(r"\[\d+\]"))


def test_the_model_answer_passes_the_visible_check(page: Page, screenshots: Path) -> None:
    with step(page, screenshots, "03-model-answer-passes-its-check"):
        check = write_blank_and_run(page, model_answer())
        expect(check.locator(".jp-OutputArea-output")).to_contain_text("all visible checks passed")
    output = check.locator(".jp-OutputArea").text_content()
    assert "Error" not in output, output


def test_a_catalogued_mistake_fails_the_visible_check_with_a_message(page: Page, screenshots: Path) -> None:
    with step(page, screenshots, "04-mistake-fails-its-check"):
        check = write_blank_and_run(page, mistaken_answer())
        expect(check.locator(".jp-OutputArea-output")).to_contain_text("AssertionError")
    output = check.locator(".jp-OutputArea").text_content()
    assert "all visible checks passed" not in output, output
    # A check's verdict on a wrong answer, which names the case it tried (not a crash in the blank).
    assert "diag(4, 9)" in output, f"The check's message does not say which case failed: {output}"


def test_validate_fails_and_names_each_blank_to_fix(page: Page, jupyterlab: JupyterLab, screenshots: Path) -> None:
    """With the mistake in gain_information_form and every other blank unwritten, Validate (which
    saves first) reports failure and names every blank (issue 14), the code blanks first and then each
    empty written answer by its question (issue 34). Before issue 14, Validate failed on the unwritten
    written answers only ("You did not provide a response") and named no blank; before issue 34 the
    written answers, which come first in the notebook, came first, each as "YOUR ANSWER HERE"."""
    write_blank_and_run(page, mistaken_answer())
    with step(page, screenshots, "05-validate-dialog"):
        page.locator(".jp-NotebookPanel-toolbar").get_by_role("button", name="Validate").click()
        dialog = page.locator(".jp-Dialog")
        expect(dialog).to_be_visible()
        expect(dialog.locator(".jp-Dialog-header")).to_contain_text("Validat")
        body = dialog.locator(".jp-Dialog-body")
        expect(body).not_to_be_empty()
        text = body.text_content()
    dialog.get_by_role("button", name="Ok").click()
    expect(dialog).to_have_count(0)
    [saved] = [c for c in cells.read(jupyterlab.bundle / NOTEBOOK).cells if cells.meta(c).get("grade_id") == BLANK]
    assert saved.source == mistaken_answer(), "Validate did not save the notebook as typed before validating"
    assert "Success" not in text, f"Validate passed a notebook whose blanks are wrong or unwritten:\n{text}"
    assert re.search(r"fail", text, re.IGNORECASE), f"Validate's dialog does not say that it failed:\n{text}"
    unnamed = [name for name in cells.blank_names(cells.read(LAB.source_notebook)) if name not in text]
    assert not unnamed, f"Validate's dialog does not name the blanks {unnamed}:\n{text}"
    # the code blanks first, then each empty written answer by its question (issue 34; course/validate_order.py)
    first_written = text.find("You did not provide a response.")
    assert first_written > 0, f"Validate's dialog does not show the empty written answers by their question:\n{text}"
    late = [name for name in cells.blank_names(cells.read(LAB.source_notebook)) if text.index(f"graded cell of {name}") > first_written]
    assert not late, f"Validate's dialog lists the blanks {late} after a written answer:\n{text}"
    questions = [c for c in cells.read(LAB.release_notebook).cells if c.cell_type == "markdown" and cells.meta(c).get("grade")]
    assert text.count("You did not provide a response.") == len(questions), text  # said once each, by nbgrader
    assert re.search(r"Derivation 1\b[^.]*\. Show that", text) and "YOUR ANSWER HERE" not in text, text


def test_no_instructor_tool_is_shown(page: Page, screenshots: Path) -> None:
    """Neither the menus nor the sidebars offer Formgrader, Create Assignment or Assignment List;
    Validate stays. Needs the bundle's Jupyter config that hides nbgrader's instructor tools (issue 14)."""
    with step(page, screenshots, "06-no-instructor-tools"):
        expect(page.locator(".jp-NotebookPanel-toolbar").get_by_role("button", name="Validate")).to_be_visible()
        menubar = page.locator("#jp-MainMenu")
        nbgrader_menu = menubar.get_by_role("menuitem", name="Nbgrader", exact=True)
        if nbgrader_menu.count():
            nbgrader_menu.click()
            expect(page.locator(".lm-Menu")).to_be_visible()
        shown = page.locator(".lm-Menu, .jp-SideBar, #jp-MainMenu, .lm-DockPanel-tabBar").all_text_contents()
    page.keyboard.press("Escape")
    offered = [tool for tool in INSTRUCTOR_TOOLS if any(tool.lower() in text.lower() for text in shown)]
    assert not offered, f"A student's JupyterLab offers instructor tools: {', '.join(offered)}"

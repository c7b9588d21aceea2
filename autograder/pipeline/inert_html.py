"""A submission's notebook made such that every page rendered from it is sanitised HTML.

nbgrader's formgrader shows a graded notebook to the instructor as a page of the Jupyter server
itself, rendered by nbconvert from ``autograded/`` with nbgrader's own template: a script from a
submission would run there as the instructor, with the server's API, which reads the reference,
opens terminals and changes grades. The kit's feedback pages render the same notebook. Neither
template sanitises what it renders, so ``InertHtml`` makes the notebook's content such that what
nbconvert renders from it is the sanitiser's output (``autograder.pipeline.sanitise``):

- a Markdown cell is kept as written if its rendering (``markdown2html | strip_files_prefix``, as
  both templates do) is exactly what the sanitiser makes of it (an unanswered written answer is,
  so nbgrader's checksum still tells it from an answer). Otherwise its source becomes that
  sanitised HTML in a ``<div>`` on one line (newlines written ``&#10;``), if that renders to
  itself (Markdown passes such a block through); else the cell's text escaped in a ``<pre>``, if
  that renders to itself; else nothing;
- a raw cell holds the sanitised HTML of its source;
- an output keeps only plain text (which nbconvert escapes) and PNG or JPEG images, whose data is
  checked as base64 and whose metadata keeps only whole-number widths and heights: nbconvert
  writes those into ``<img>`` unquoted.

It runs in autograde right after the kernel, so that ``autograded/`` holds the cleaned notebook
for every later renderer, and again when feedback is generated (from notebooks graded before it).
"""

from __future__ import annotations

import base64
import binascii
import re
import time

from nbconvert.exporters import HTMLExporter
from nbconvert.filters.strings import strip_files_prefix
from nbformat import NotebookNode
from nbgrader.preprocessors import NbGraderPreprocessor

from autograder.pipeline.sanitise import inert_tex, sanitise

SHOWN = ("text/plain", "image/png", "image/jpeg")
"""The kinds of displayed data an output keeps."""
IMAGES = ("image/png", "image/jpeg")
SIZE = re.compile(r"[0-9]{1,5}")
"""An image's width or height as the metadata may give it."""
_exporter = HTMLExporter()


def rendered(source: str, attachments: dict | None = None) -> str:
    """The HTML that nbconvert's templates (nbgrader's feedback and formgrade) render from a
    Markdown cell's ``source``."""
    context = {"cell": {"attachments": attachments or {}}, "resources": {}}
    return strip_files_prefix(_exporter.markdown2html(context, source))


def _one_line(markup: str) -> str:
    return "<div>" + markup.replace("\r", "&#13;").replace("\n", "&#10;") + "</div>"


def _as_text(source: str) -> str:
    """``source`` as text in a ``<pre>`` (its TeX made inert), every character but letters, digits and
    spaces escaped."""
    escaped = "".join(c if c.isalnum() and c.isascii() or c == " " else f"&#{ord(c)};" for c in inert_tex(source))
    return f"<div><pre>{escaped}</pre></div>"


MAX_MARKDOWN_CHARS = 10_000
"""The longest Markdown cell rendered as Markdown (a lab's longest has about 4,800 characters); a longer one is
shown as text. nbconvert's Markdown takes time quadratic in some texts: 30,000 characters of ``\\(`` took 6.5 s,
150,000 took two minutes of a grading worker (an adversarial review of issue 36)."""


MARKDOWN_SECONDS = 10.0
"""The time one notebook's Markdown may take to render (a lab's takes well under a second); the cells after it is
spent are shown as text. The cap on a cell does not cap a notebook: twelve cells of 10,000 characters each took 40 s
of the grader's process (the re-attack of issue 36's review)."""


def inert_markdown(cell: NotebookNode, render: bool = True) -> None:
    """Make ``cell`` (Markdown) render to sanitised HTML (see the module's doc); without ``render``, show it as text."""
    attachments = cell.get("attachments")
    try:
        page = rendered(cell.source, attachments) if render and len(cell.source) <= MAX_MARKDOWN_CHARS else None
    except Exception:  # noqa: BLE001 (nbconvert cannot render it, e.g. an attachment it names is missing: show it as text)
        page = None
    clean = sanitise(page) if page is not None else None
    if page is not None and page == clean:
        return
    cell.pop("attachments", None)
    for source in ((_one_line(clean),) if clean is not None else ()) + (_as_text(cell.source),):
        if rendered(source).rstrip("\n") == source:
            cell.source = source
            return
    cell.source = ""


def inert_output(output: NotebookNode) -> bool:
    """Make ``output`` inert; False if nothing of it is left to show."""
    if "data" not in output:
        return True
    data = {}
    for kind, value in output.data.items():
        if kind in IMAGES:
            try:
                value = base64.b64encode(base64.b64decode("".join(value).encode("ascii"), validate=False)).decode()
            except (binascii.Error, UnicodeEncodeError, ValueError):
                continue
        if kind in SHOWN:
            data[kind] = value
    output.data = data
    if "metadata" in output:
        output.metadata = {kind: {key: int(value) for key, value in output.metadata[kind].items()
                                  if key in ("width", "height") and SIZE.fullmatch(str(value))}
                           for kind in IMAGES if kind in data and isinstance(output.metadata.get(kind), dict)}
    return bool(data)


class InertHtml(NbGraderPreprocessor):
    """Markdown, raw cells and outputs whose every rendering is sanitised (see the module doc)."""

    def preprocess(self, nb: NotebookNode, resources: dict) -> tuple[NotebookNode, dict]:
        self._markdown_seconds = 0.0
        return super().preprocess(nb, resources)

    def preprocess_cell(self, cell: NotebookNode, resources: dict, index: int) -> tuple[NotebookNode, dict]:
        if cell.cell_type == "markdown":
            start = time.monotonic()
            inert_markdown(cell, render=self._markdown_seconds < MARKDOWN_SECONDS)
            self._markdown_seconds += time.monotonic() - start
        elif cell.cell_type == "raw":
            cell.source = sanitise(cell.source)
        elif cell.cell_type == "code":
            cell.outputs = [output for output in cell.outputs if inert_output(output)]
        return cell, resources

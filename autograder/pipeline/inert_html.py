"""A submission's HTML made inert before anyone views the graded notebook.

nbgrader's formgrader shows a graded notebook to the instructor as a page of the Jupyter server
itself, and renders what the notebook holds as HTML: a script in a student's Markdown cell (an
``<img onerror=...>`` will do) or in an output (``text/html``, ``text/markdown``,
``application/javascript``) runs there as the instructor, with the server's API, which reads the
reference, opens terminals and changes grades. The kit's feedback pages render the same notebook.
``InertHtml`` runs right after the kernel, on the notebook they show: in Markdown and raw cells a
space follows each ``<`` that would open a tag (``<`` before a letter, ``/``, ``?`` or ``!``, but
not a comment's ``<!--``), so that no tag is left and the text reads the same (``x<y`` becomes
``x< y``, in math too); outputs keep only plain text and PNG or JPEG images. The labs' own cells
hold no tag (only comments, the claims' markers) and their outputs are text and PNG figures, so an
honest notebook looks the same; the grader's note escapes its text already.
"""

from __future__ import annotations

import re

from nbformat import NotebookNode
from nbgrader.preprocessors import NbGraderPreprocessor

from autograder.pipeline.restore import is_grader_note

SHOWN = ("text/plain", "image/png", "image/jpeg")
"""The kinds of displayed data an output keeps."""
TAG_OPENING = re.compile(r"<(?=[A-Za-z/?]|!(?!--))")
"""A ``<`` that opens a tag, a closing tag, a declaration or a processing instruction."""


class InertHtml(NbGraderPreprocessor):
    """Markdown cells with no tag left, outputs with no HTML or script (see the module doc)."""

    def preprocess_cell(self, cell: NotebookNode, resources: dict, index: int) -> tuple[NotebookNode, dict]:
        if cell.cell_type in ("markdown", "raw") and not is_grader_note(cell):
            cell.source = TAG_OPENING.sub("< ", cell.source)
        if cell.cell_type == "code":
            kept = []
            for output in cell.outputs:
                if "data" in output:
                    output.data = {kind: value for kind, value in output.data.items() if kind in SHOWN}
                    if not output.data:
                        continue
                kept.append(output)
            cell.outputs = kept
        return cell, resources

"""The class report's HTML page of one lab: counts only (no student is named), so that it can be
shown in a lecture.

The page is one self-contained file: its style inline, its figure embedded as a ``data:`` PNG, no
script, and a Content-Security-Policy that lets it load nothing else. Every piece of text that is
not the kit's own (an error's name from a submission, a cell id, a mistake's hint) is escaped with
``html.escape``: the page shows text as text, never as markup.
"""

from __future__ import annotations

import base64
from html import escape
from pathlib import Path

from autograder.pipeline.class_counts import BlankCounts, LabCounts

WRONG_ONLY_LEAD = "wrong only on the cases with"
"""How the detail of a loss grouped by the kind of case alone wrong begins (class_report.WRONG_ONLY)."""

STYLE = """
body { font-family: system-ui, sans-serif; max-width: 60rem; margin: 2rem auto; padding: 0 1rem; color: #222; }
h1 { font-size: 1.5rem; } h2 { font-size: 1.2rem; margin-top: 2rem; } h3 { font-size: 1rem; margin: 1.2rem 0 0.3rem; }
table { border-collapse: collapse; margin: 0.3rem 0; } td, th { padding: 0.15rem 0.6rem; text-align: left; vertical-align: top; }
th { border-bottom: 1px solid #999; } td:first-child { min-width: 13rem; }
td.n { text-align: right; min-width: 3rem; font-variant-numeric: tabular-nums; }
td.hint { color: #444; font-size: 0.9rem; max-width: 36rem; overflow-wrap: anywhere; }
.bar { display: inline-block; height: 0.8rem; background: #3a7bbf; vertical-align: middle; }
img { max-width: 100%; } p.note { color: #555; font-size: 0.9rem; }
table.blank { table-layout: fixed; width: 100%; } table.blank td:first-child { overflow-wrap: anywhere; }
td.sub { padding-left: 1.6rem; color: #444; }
"""
CSP = "default-src 'none'; img-src data:; style-src 'unsafe-inline'"
"""Nothing loads but the embedded figure and the inline style; no script runs."""


def _rows(rows: list[tuple[str, int, str]]) -> str:
    """Table rows of (what, count, comment)."""
    return "".join(f'<tr><td>{escape(what)}</td><td class="n">{n}</td><td class="hint">{escape(comment)}</td></tr>'
                   for what, n, comment in rows)


def _blank_section(counts: LabCounts, blank: BlankCounts) -> str:
    """A blank's counts: full marks, each catalogued mistake with its hint, lost another way (by the
    kind of case alone wrong, or the failing error's name), not written."""
    rows = [("full marks", len(blank.full), "")]
    rows += [(f"mistake: {slug}", len(students), counts.mistakes[blank.blank, slug].hint)
             for slug, students in blank.mistakes.items()]
    narrowed = {detail: students for detail, students in blank.other.items() if detail.startswith(WRONG_ONLY_LEAD)}
    rows.append(("lost another way", len(blank.other_students),
                 ", ".join(f"{name}: {len(students)}" for name, students in blank.other.items() if name not in narrowed)))
    after = [("not written", len(blank.not_written), ""),
             ("visible checks failed", len(blank.visible_failed), "")]
    sub = "".join(f'<tr><td class="sub">{escape(detail)}</td><td class="n">{len(students)}</td><td></td></tr>'
                  for detail, students in narrowed.items())
    return (f'<h3>{escape(blank.blank)}</h3><table class="blank"><colgroup><col style="width:17rem">'
            f'<col style="width:4rem"><col></colgroup>{_rows(rows)}{sub}{_rows(after)}</table>')


def render(counts: LabCounts, figure_png: bytes) -> str:
    """The page of one lab's counts, with its figure (PNG bytes) embedded."""
    n = len(counts.students)
    bins = counts.score_bins()
    widest = max((len(students) for _, students in bins), default=0) or 1
    histogram = "".join(f'<tr><td class="n">{escape(label)}</td><td class="n">{len(students)}</td>'
                        f'<td><span class="bar" style="width:{12 * len(students) / widest:.2f}rem"></span></td></tr>'
                        for label, students in bins)
    waiting = (f"<table>{_rows([(cell, len(students), '') for cell, students in counts.waiting.items()])}</table>"
               if counts.waiting else "<p>This lab has no written answers.</p>")
    figure = base64.b64encode(figure_png).decode()
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta http-equiv="Content-Security-Policy" content="{CSP}">
<title>{escape(counts.lab)}: what the class got wrong</title><style>{STYLE}</style></head>
<body>
<h1>{escape(counts.lab)}: what the class got wrong</h1>
<p>{n} graded submissions. Counts only: the students behind each count are in {escape(counts.lab)}-students.csv,
for the instructor.</p>
<img alt="One bar per blank: full marks, each catalogued mistake, lost another way, not written"
 src="data:image/png;base64,{figure}">
<h2>Autograded scores</h2>
<p class="note">Points from the hidden tests, out of {counts.auto_max:g}, before any late penalty; written answers are
graded by hand.</p>
<table><tr><th>score</th><th>students</th><th></th></tr>{histogram}</table>
<h2>Each blank</h2>
<p class="note">A catalogued mistake is one the grader diagnosed while grading: on every hidden case, the student's
function gave that mistake's results. Lost another way: the test failed otherwise, grouped by the kind of case
that alone it was wrong on when its cases split so ("wrong only on the cases with a full R"), else by the failing
error's name. Visible checks failed: the blank was written and handed in with a visible check that raised an error
when graded, whatever its score (information only, never part of a score).</p>
{"".join(_blank_section(counts, blank) for blank in counts.blanks)}
<h2>Submissions to look at</h2>
<table>{_rows([("flagged for review", len(counts.flagged), "the integrity scan found something"),
               ("late", len(counts.late), "a late penalty was taken"),
               ("faulted", len(counts.faulted), "the grader noted a change or a fault: a stopped cell, a dead "
                "kernel, restored cells, cut output"),
               ("visible checks failed", len(counts.visible_failed), "handed in with a written blank whose "
                "visible checks raised an error; not part of any score")])}</table>
<h2>Written answers waiting for a hand grade</h2>
{waiting}
</body></html>
"""


def write(counts: LabCounts, figure: Path, path: Path) -> Path:
    """Write the page of ``counts`` with the PNG ``figure`` embedded to ``path``; returns ``path``."""
    path.write_text(render(counts, figure.read_bytes()), encoding="utf-8")
    return path

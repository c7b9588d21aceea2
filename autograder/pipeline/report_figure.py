"""The class report's figure: one horizontal bar per blank, split into full marks, each catalogued
mistake (a colour of its own, named in the legend), lost another way, and not written.

The bars count students, so a bar is as long as the class; a segment wide enough for it shows its
count, so that the figure reads the same for 5 students and for 500. Drawn with matplotlib's Agg
canvas (no display, no pyplot state).
"""

from __future__ import annotations

from pathlib import Path

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure

from autograder.pipeline.class_counts import LabCounts

FULL_COLOUR, OTHER_COLOUR, NOT_WRITTEN_COLOUR = "#3a8f3a", "#8c8c8c", "#e4e4e4"
MISTAKE_COLOURS = ("#1f77b4", "#ff7f0e", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#bcbd22",
                   "#aec7e8", "#ffbb78", "#ff9896", "#c5b0d5", "#c49c94", "#f7b6d2", "#9edae5", "#dbdb8d")
"""The mistakes' colours (none green or grey); past 16 mistakes they repeat, hatched."""
HATCHES = ("", "//", "..", "xx")
LABEL_SHARE = 0.04
"""A segment shows its count when it is at least this share of the class."""


def draw(counts: LabCounts, path: Path) -> Path:
    """Draw the figure of one lab's counts into the PNG ``path``; returns ``path``."""
    blanks = list(reversed(counts.blanks))  # the notebook's first blank on top
    present = [(b.blank, slug) for b in counts.blanks for slug in b.mistakes]
    styles = {key: (MISTAKE_COLOURS[k % len(MISTAKE_COLOURS)], HATCHES[k // len(MISTAKE_COLOURS) % len(HATCHES)])
              for k, key in enumerate(present)}
    total = max(len(counts.students), 1)
    figure = Figure(figsize=(9, 1.2 + 0.45 * len(blanks) + 0.22 * (len(present) + 3) / 2), layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.subplots()
    handles: dict[str, object] = {}
    for y, blank in enumerate(blanks):
        segments = [("full marks", len(blank.full), FULL_COLOUR, "")]
        segments += [(f"{blank.blank}: {slug}", len(students), *styles[blank.blank, slug])
                     for slug, students in blank.mistakes.items()]
        segments += [("lost another way", len(blank.other_students), OTHER_COLOUR, ""),
                     ("not written", len(blank.not_written), NOT_WRITTEN_COLOUR, "")]
        left = 0
        for label, width, colour, hatch in segments:
            if not width:
                continue
            [bar] = axes.barh(y, width, left=left, height=0.7, color=colour, hatch=hatch, edgecolor="white", linewidth=0.5)
            handles.setdefault(label, bar)
            if width / total >= LABEL_SHARE:
                axes.text(left + width / 2, y, str(width), ha="center", va="center", fontsize=8,
                          color=_text_colour(colour))
            left += width
    axes.set_yticks(range(len(blanks)), [b.blank for b in blanks], fontsize=9)
    axes.set_xlim(0, total)
    axes.set_xlabel("students")
    axes.set_title(f"{counts.lab}: {len(counts.students)} graded submissions, each blank's outcome", fontsize=11)
    axes.spines[["top", "right"]].set_visible(False)
    order = ["full marks", *[f"{b}: {s}" for b, s in present], "lost another way", "not written"]
    shown = [label for label in order if label in handles]
    figure.legend([handles[label] for label in shown], shown, loc="outside lower center", ncols=2 if len(shown) > 4 else 4,
                  fontsize=8, frameon=False)
    figure.savefig(path, dpi=110)
    return path


def _text_colour(colour: str) -> str:
    """Black on a light colour, white on a dark one (by its relative luminance)."""
    red, green, blue = to_rgb(colour)
    return "black" if 0.2126 * red + 0.7152 * green + 0.0722 * blue > 0.5 else "white"

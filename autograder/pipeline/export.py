"""``nbgrader export`` in the kit's format: the grades CSV that ``python -m autograder grade`` writes.

After grading the written answers in formgrader, run ``nbgrader export`` from the course root
(``nbgrader_config.py`` makes this plugin its exporter): ``grades.csv`` is rewritten from the
gradebook with the manual scores, without grading anything again. ``--to FILE`` writes elsewhere;
``--CourseDirectory.root=WORKDIR`` exports a course graded with ``grade --workdir WORKDIR``.
"""

from __future__ import annotations

from pathlib import Path

from nbgrader.api import Gradebook
from nbgrader.plugins import ExportPlugin

from autograder.pipeline import grades
from autograder.labs import ROOT, Lab


class GradesExport(ExportPlugin):
    """One row per student and lab, one column per graded cell (``grades.write_csv``), and the
    environment record beside it (``versions.record``)."""

    def export(self, gradebook: Gradebook) -> None:
        workdir = Path(self.parent.coursedir.root)
        dest = Path(self.to) if self.to else workdir / "grades.csv"
        wanted = set(self.assignment)
        labs = [Lab(a.name) for a in gradebook.assignments
                if (ROOT / "source" / a.name).is_dir() and (not wanted or a.name in wanted)]
        rows = grades.read_grades(workdir, labs, [str(s) for s in self.student] or None)
        grades.write_grades(rows, dest)
        self.log.info("Exported %d grade rows to %s", len(rows), dest)

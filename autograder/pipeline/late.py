"""Late submissions: the labs' due dates, and the penalty nbgrader applies after their due date.

The due dates live in ``due_dates.toml`` (course root). ``python -m autograder grade`` writes them
into the gradebook (nbgrader's ``Assignment.duedate``) before it autogrades, so that nbgrader's
``AssignLatePenalties`` sees how late each submission is from its ``timestamp.txt``. A submission
without a ``timestamp.txt`` is never late. ``nbgrader_config.py`` sets the penalty: ``LatePenalty``.
"""

from __future__ import annotations

import math
import tomllib
from datetime import datetime
from pathlib import Path

from nbgrader.api import Gradebook
from nbgrader.coursedir import CourseDirectory
from nbgrader.plugins import BasePlugin
from traitlets import Float
from traitlets.config import Config

from autograder.labs import DUE_DATES, Lab, all_labs

SECONDS_PER_DAY = 86400


class LatePenalty(BasePlugin):
    """nbgrader late-submission plugin: ``percent_per_day`` of the points earned, for every day or
    part of a day late, at most ``max_percent``."""

    percent_per_day = Float(10.0, help="Percent of the earned points taken per started day late.").tag(config=True)
    max_percent = Float(50.0, help="The largest penalty, in percent of the earned points.").tag(config=True)

    def late_submission_penalty(self, student_id: str, score: float, total_seconds_late: float) -> float:
        """The points taken from ``score``, the notebook's score when nbgrader autogrades it."""
        days = math.ceil(total_seconds_late / SECONDS_PER_DAY)
        return score * min(self.percent_per_day * days, self.max_percent) / 100.0


def read_due_dates(path: Path) -> dict[str, datetime]:
    """Lab id -> due date (timezone-aware), from the ``[due]`` table of a TOML file.

    Raises ValueError for a lab that does not exist or a date without its UTC offset.
    """
    with open(path, "rb") as handle:
        due = tomllib.load(handle).get("due", {})
    labs = {lab.id for lab in all_labs()}
    for lab_id, date in due.items():
        if lab_id not in labs:
            raise ValueError(f"{path}: there is no lab {lab_id!r}. The labs are: {', '.join(sorted(labs))}.")
        if not isinstance(date, datetime) or date.tzinfo is None:
            raise ValueError(f"{path}: the due date of {lab_id} must be a date and time with its UTC offset, "
                             f"e.g. 2026-10-02T23:59:00+01:00 (it is {date!r}).")
    return due


def set_due_dates(labs: list[Lab], config: Config) -> None:
    """Write each lab's due date from ``due_dates.toml`` into the gradebook of the course
    configuration ``config`` (a lab without a date there: no due date, never late)."""
    due = read_due_dates(DUE_DATES)
    with Gradebook(CourseDirectory(config=config).db_url) as gb:
        for lab in labs:
            gb.update_or_create_assignment(lab.id, duedate=due.get(lab.id))

"""nbgrader configuration of the Estimation Lab Kit. Run nbgrader from this folder (the course root).

Plain `nbgrader generate_assignment train-kf` and `nbgrader autograde train-kf` work with it, and so
does `python -m autograder`, which loads this same file.
"""

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent

# The grading kernel must import the hidden reference package `solutions` and the hidden-test
# helpers in `autograder`, which live here and are never installed. Kernels inherit this variable.
# The autograder's preprocessors are imported from here too.
sys.path.insert(0, str(ROOT))
os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH")) if p)
# nbgrader runs `alembic` to create a gradebook; find it beside this Python even in an environment
# that was not activated (`.venv/bin/python -m autograder ...`).
os.environ["PATH"] = os.pathsep.join((os.path.dirname(sys.executable), os.environ.get("PATH", "")))

from autograder.execute import ExecuteWithReference  # noqa: E402
from course.checks import NOT_WRITTEN  # noqa: E402
from nbconvert.preprocessors import ClearMetadataPreprocessor, CSSHTMLHeaderPreprocessor  # noqa: E402
from nbgrader.preprocessors import (  # noqa: E402
    AssignLatePenalties,
    CheckCellMetadata,
    ClearHiddenTests,
    GetGrades,
    IgnorePattern,
    LimitOutput,
    SaveAutoGrades,
)

c = get_config()  # noqa: F821 (provided by traitlets when it loads this file)

c.CourseDirectory.course_id = "estimation-lab-kit"

# What students see in place of the model answers.
# `course.checks.require` recognises a stub by its message.
c.ClearSolutions.code_stub = {"python": f'# YOUR CODE HERE\nraise NotImplementedError("{NOT_WRITTEN}")'}
c.ClearSolutions.text_stub = "YOUR ANSWER HERE"

# Grading. A deleted or edited test cell is restored from the gradebook before grading, and the
# kernel must import `solutions` (ExecuteWithReference refuses to grade otherwise).
c.OverwriteCells.add_missing_cells = True
c.Execute.timeout = 60
# The kernel's own log goes to the grader's terminal, never into the graded notebook. At WARNING
# level ipykernel 7 prints a notice about unencrypted loopback TCP for every submission, which
# buries the grading summary; errors still show.
c.Execute.extra_arguments = ["--HistoryManager.hist_file=:memory:", "--IPKernelApp.log_level=ERROR"]
c.Autograde.autograde_preprocessors = [
    ExecuteWithReference,
    IgnorePattern,
    ClearMetadataPreprocessor,
    LimitOutput,
    SaveAutoGrades,
    AssignLatePenalties,
    CheckCellMetadata,
]

# Feedback shows students their graded notebook without the hidden tests' code.
c.GenerateFeedback.preprocessors = [GetGrades, CSSHTMLHeaderPreprocessor, ClearHiddenTests]

"""nbgrader configuration of the Estimation Lab Kit. Run nbgrader from this folder (the course root).

Plain `nbgrader generate_assignment train-kf` and `nbgrader autograde train-kf` work with it, and so
does `python -m autograder`, which loads this same file.
"""

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent

# The grader's process imports the autograder's preprocessors, the hidden tests and the reference
# `solutions` from here; they are never installed. Grading kernels do not get this path: the hidden
# tests compare in the grader's process (autograder/pipeline/check_runner.py), and the kernel needs only `course`.
sys.path.insert(0, str(ROOT))
# nbgrader runs `alembic` to create a gradebook; find it beside this Python even in an environment
# that was not activated (`.venv/bin/python -m autograder ...`).
os.environ["PATH"] = os.pathsep.join((os.path.dirname(sys.executable), os.environ.get("PATH", "")))

from autograder.pipeline.execute import GradingExecute  # noqa: E402
from autograder.kernel.manager import SandboxedKernelManager  # noqa: E402
from autograder.integrity.flag import FlagCheating  # noqa: E402
from autograder.pipeline.inert_html import InertHtml  # noqa: E402
from autograder.pipeline.restore import RestoreLabCells  # noqa: E402
from autograder.pipeline.verdicts import GraderScores  # noqa: E402
from course.checks import NOT_WRITTEN  # noqa: E402
from nbconvert.preprocessors import ClearMetadataPreprocessor, CSSHTMLHeaderPreprocessor  # noqa: E402
from nbgrader.preprocessors import (  # noqa: E402
    AssignLatePenalties,
    CheckCellMetadata,
    ClearHiddenTests,
    ClearOutput,
    DeduplicateIds,
    IgnorePattern,
    LimitOutput,
    OverwriteCells,
    OverwriteKernelspec,
)

c = get_config()  # noqa: F821 (provided by traitlets when it loads this file)

c.CourseDirectory.course_id = "estimation-lab-kit"

# The gradebook: nbgrader's default is SQLite, `gradebook.db` in the course folder. A course with
# several graders can keep it in a database server instead: set GRADEBOOK_URL to its SQLAlchemy
# URL, e.g. postgresql+psycopg://USER:PASSWORD@HOST:5432/DATABASE (driver: environment.txt).
if os.environ.get("GRADEBOOK_URL"):
    c.CourseDirectory.db_url = os.environ["GRADEBOOK_URL"]

# What students see in place of the model answers.
# `course.checks.require` recognises a stub by its message.
c.ClearSolutions.code_stub = {"python": f'# YOUR CODE HERE\nraise NotImplementedError("{NOT_WRITTEN}")'}
c.ClearSolutions.text_stub = "YOUR ANSWER HERE"

# Grading. A deleted or edited test cell is restored from the gradebook before grading. The grader
# must import the hidden tests (GradingExecute refuses to grade otherwise), and each kernel is capped:
# memory, time per cell, time per submission, output per cell. A kernel that dies or hangs is
# restarted and the cells before the fatal one are replayed (see autograder/pipeline/execute.py).
c.OverwriteCells.add_missing_cells = True
# Each grading kernel runs in the sandbox (autograder/kernel/sandbox.py): it reads only the Python
# installation and course/, writes only its submission's folder and a private one, and has no
# network. Where the OS cannot sandbox, grading runs anyway and says so (KIT_SANDBOX=off turns it off).
c.GradingExecute.kernel_manager_class = SandboxedKernelManager
# GRADING_CELL_TIMEOUT lowers the time per cell, e.g. for the tests' deliberately stuck submissions.
c.Execute.timeout = int(os.environ.get("GRADING_CELL_TIMEOUT", "30"))
c.GradingExecute.memory_limit_gb = 4.0
c.GradingExecute.notebook_timeout = 300
c.GradingExecute.max_output_bytes = 1_000_000
# A kernel gets 3 minutes to start, not nbclient's 60 s: on a loaded machine (more grading jobs
# than cores, or other work beside them) a start took longer than 60 s, and nbgrader then drops the
# whole submission from the batch. Once, even 180 s was not enough (a full test run beside other
# grading on two cores); a kernel that does not answer is shut down and another started, three
# starts in all, before the submission is reported as not graded.
c.Execute.startup_timeout = 180
c.GradingExecute.kernel_start_attempts = 3
# The kernel's own log goes to the grader's terminal, never into the graded notebook. At WARNING
# level ipykernel 7 prints a notice about unencrypted loopback TCP for every submission, which
# buries the grading summary; errors still show.
c.Execute.extra_arguments = ["--HistoryManager.hist_file=:memory:", "--IPKernelApp.log_level=ERROR"]
# Before grading, a submission's cells are put back in the lab's order, with any lab cell it lost.
c.Autograde.sanitize_preprocessors = [
    ClearOutput,
    DeduplicateIds,
    RestoreLabCells,
    OverwriteKernelspec,
    OverwriteCells,
    CheckCellMetadata,
]
# After execution, the integrity findings (static scan and the kernel's monitor) take away the
# points of every blank a submission games, and flag it for review (autograder/integrity/flag.py).
# The score of each test cell is the grader's verdict alone (GraderScores, in place of nbgrader's
# SaveAutoGrades, which reads the score from what the kernel left in the cell's outputs; see
# autograder/pipeline/verdicts.py).
c.Autograde.autograde_preprocessors = [
    GradingExecute,
    FlagCheating,
    InertHtml,
    IgnorePattern,
    ClearMetadataPreprocessor,
    LimitOutput,
    GraderScores,
    AssignLatePenalties,
    CheckCellMetadata,
]

# InertHtml comes after FlagCheating, whose notes quote the student's code, so that they are made inert
# too. ClearMetadataPreprocessor (which nbconvert leaves disabled) keeps only the notebook metadata the
# pages need: a submission's own (widget state, a title) would otherwise reach any other renderer of
# the graded notebook, such as a plain `jupyter nbconvert --to html`, which loads widgets from it.
c.ClearMetadataPreprocessor.enabled = True
c.ClearMetadataPreprocessor.clear_cell_metadata = False
c.ClearMetadataPreprocessor.preserve_nb_metadata_mask = {("kernelspec",), ("language_info",)}

# Feedback shows students their graded notebook without the hidden tests' code, with the kit's
# template over nbgrader's: written answers not graded yet say so, a test cell that earns its marks
# under a failed visible check says why, long messages wrap (autograder/pipeline/feedback.py).
from autograder.pipeline.feedback import NBGRADER_TEMPLATES, TEMPLATE, TEMPLATE_PATHS, TEMPLATES, FeedbackGrades  # noqa: E402

# InertHtml again and the template's `kit_sanitise`: what a page renders from a submission is
# sanitised HTML, also from a notebook graded before the sanitiser (autograder/pipeline/sanitise.py),
# with its TeX as MathML: the page loads no MathJax, nor any other script.
from autograder.pipeline.sanitise import sanitise_math  # noqa: E402

c.GenerateFeedback.preprocessors = [InertHtml, FeedbackGrades, CSSHTMLHeaderPreprocessor, ClearHiddenTests]
c.GenerateFeedback.HTMLExporter.filters = {"kit_sanitise": sanitise_math}
c.GenerateFeedback.HTMLExporter.template_name = TEMPLATE
c.GenerateFeedback.HTMLExporter.extra_template_basedirs = [str(NBGRADER_TEMPLATES), str(TEMPLATES)]
c.GenerateFeedback.HTMLExporter.extra_template_paths = TEMPLATE_PATHS

# Late submissions: the labs' due dates are in due_dates.toml (`python -m autograder grade` writes
# them into the gradebook). A late submission loses percent_per_day of its earned points for every
# started day late, at most max_percent (autograder/pipeline/late.py).
from autograder.pipeline.late import LatePenalty  # noqa: E402

c.AssignLatePenalties.plugin_class = LatePenalty
c.LatePenalty.percent_per_day = 10.0
c.LatePenalty.max_percent = 50.0

# `nbgrader export` rewrites grades.csv from the gradebook in the kit's format, with the scores
# given by hand in formgrader, without grading again (autograder/pipeline/export.py).
from autograder.pipeline.export import GradesExport  # noqa: E402

c.ExportApp.plugin_class = GradesExport

# `nbgrader zip_collect` unpacks an LMS download within limits: no archive inside an archive, no
# link, no path out of the folder, capped size, file count and compression ratio; what it refuses
# is logged and stays in the download (autograder/pipeline/archives.py).
c.ZipCollectApp.extractor_plugin = "autograder.pipeline.collect.SafeExtractor"

"""Running nbgrader's converters (generate_assignment, autograde, generate_feedback) in-process on a
course folder, with the course's nbgrader_config.py.

Everything runs through nbgrader's converters in this process, so that a batch of submissions costs
one nbgrader start-up, not one per submission. A ``workdir`` is an nbgrader course directory
(gradebook, submitted/, autograded/, feedback/); the course root is the default, and the demo and
the tests use a temporary one. The labs' sources always come from the course root.
"""

from __future__ import annotations

import functools
import warnings
from pathlib import Path

import nbgrader.api
from alembic.config import Config as AlembicConfig
from alembic.script import ScriptDirectory
from nbgrader.converters import GenerateAssignment
from nbgrader.coursedir import CourseDirectory
from nbgrader.utils import capture_log
from sqlalchemy.exc import SAWarning
from traitlets.config import Config
from traitlets.config.loader import PyFileConfigLoader

from autograder.labs import ROOT, Lab

# nbgrader 0.9.6 builds gradebook objects that SQLAlchemy 2 no longer adds to the session through
# backrefs; nbgrader adds them explicitly right after, so the warning is noise for every submission.
NBGRADER_SESSION_WARNING = r"Object of type <\w+> not in session, add operation along"
warnings.filterwarnings("ignore", message=NBGRADER_SESSION_WARNING, category=SAWarning)


@functools.cache
def gradebook_schema_version() -> str:
    """The revision that nbgrader writes into a new gradebook's ``alembic_version``: the head of its
    own migration scripts, read in this process.

    nbgrader 0.9 finds it by running ``alembic heads`` in a subprocess each time it creates a
    gradebook, which costs about 2 s on a quiet machine (a new Python that imports SQLAlchemy and
    Alembic): a second of every shard that sets up its gradebook, and minutes of the tests, which
    make a gradebook for each class they grade. tests/test_gradebook_sql.py checks that both give
    the same revision.
    """
    config = AlembicConfig()
    config.set_main_option("script_location", str(Path(nbgrader.api.__file__).parent / "alembic"))
    return ScriptDirectory.from_config(config).get_current_head()


nbgrader.api.get_alembic_version = gradebook_schema_version


class GradingError(RuntimeError):
    """nbgrader reported a failure; the message carries its log."""


def course_config(workdir: Path = ROOT) -> Config:
    """The course's nbgrader configuration, pointed at ``workdir``."""
    config = PyFileConfigLoader("nbgrader_config.py", path=str(ROOT)).load_config()
    config.CourseDirectory.root = str(workdir)
    config.CourseDirectory.source_directory = str(ROOT / "source")
    if "db_url" not in config.CourseDirectory:
        # Grading processes (grade --jobs) share one SQLite gradebook: each waits for the lock.
        config.CourseDirectory.db_url = f"sqlite:///{workdir / 'gradebook.db'}?timeout=120"
    return config


def gradebook_url(workdir: Path = ROOT) -> str:
    """The SQLAlchemy URL of the gradebook of the course ``workdir``."""
    return CourseDirectory(config=course_config(workdir)).db_url


def _coursedir(workdir: Path, lab: Lab, student: str) -> CourseDirectory:
    config = course_config(workdir)
    coursedir = CourseDirectory(config=config)
    coursedir.assignment_id = lab.id
    coursedir.student_id = student
    return coursedir


def run_app(app_class: type, workdir: Path, lab: Lab, student: str = "*", submitted: str | None = None) -> dict:
    """Run one nbgrader converter on a lab (every student, or one), autograde reading the submissions from
    the folder ``submitted`` of ``workdir`` when it is given; nbgrader's ``capture_log`` result."""
    coursedir = _coursedir(workdir, lab, student)
    if submitted is not None:
        coursedir.submitted_directory = submitted
    app = app_class(coursedir=coursedir, config=coursedir.config)
    app.force = True
    return capture_log(app)


def run_checked(app_class: type, workdir: Path, lab: Lab) -> None:
    """Run one nbgrader converter on every student of a lab; raise GradingError, with its log, if it fails."""
    result = run_app(app_class, workdir, lab)
    if not result["success"]:
        raise GradingError(f"nbgrader {app_class.__name__} failed for {lab.id}:\n{result.get('log', '')}{result['error']}")


def generate_release(labs: list[Lab], workdir: Path = ROOT) -> None:
    """``nbgrader generate_assignment`` for each lab: writes ``workdir/release/`` and the gradebook."""
    for lab in labs:
        run_checked(GenerateAssignment, workdir, lab)


def feedback_page(workdir: Path, lab_id: str, student: str) -> Path:
    """Where nbgrader writes a student's feedback page on a lab in the course ``workdir``."""
    return workdir / "feedback" / student / lab_id / f"{lab_id}.html"

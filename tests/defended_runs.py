"""Grading one notebook the way ``nbgrader autograde`` does, for tests that need the pieces: the
course's sanitize step against a real gradebook, then the execute step (GradingExecute with the
course's configuration), without nbgrader's converters, the scan or the gradebook's scores."""

from __future__ import annotations

import copy
from pathlib import Path

import nbformat
from nbformat import NotebookNode
from nbgrader.utils import setenv

from autograder.labs import ROOT, Lab
from course.checks import GRADING


def sanitized(nb: NotebookNode, lab: Lab, course: Path) -> NotebookNode:
    """``nb`` after the course's sanitize preprocessors (RestoreLabCells, OverwriteCells, ...), run
    against a gradebook made by nbgrader's generate_assignment, as ``nbgrader autograde`` runs them."""
    from nbgrader.converters import GenerateAssignment
    from nbgrader.coursedir import CourseDirectory
    from nbgrader.utils import capture_log
    from traitlets.config.loader import PyFileConfigLoader

    config = PyFileConfigLoader("nbgrader_config.py", path=str(ROOT)).load_config()
    config.CourseDirectory.root = str(course)
    config.CourseDirectory.source_directory = str(ROOT / "source")
    db_url = f"sqlite:///{course / 'gradebook.db'}"
    config.CourseDirectory.db_url = db_url
    course.mkdir(parents=True, exist_ok=True)
    if not (course / "release" / lab.id).exists():  # the lab is not in the gradebook yet
        coursedir = CourseDirectory(config=config)
        coursedir.assignment_id = lab.id
        app = GenerateAssignment(coursedir=coursedir, config=config)
        app.force = True
        result = capture_log(app)
        assert result["success"], result
    resources = {"nbgrader": {"notebook": lab.id, "assignment": lab.id, "student": "student", "db_url": db_url,
                              "course_id": config.CourseDirectory.course_id}}
    nb = copy.deepcopy(nb)
    for preprocessor in config.Autograde.sanitize_preprocessors:
        nb, resources = preprocessor(config=config).preprocess(nb, resources)
    return nb


def graded_run(nb_json: str, lab_id: str, course: str) -> str:
    """``nb_json`` (a sanitized notebook) after the course's GradingExecute, run from
    ``course/submitted/student/<lab_id>`` (where the catalogued cheats look for the gradebook and other students); the executed notebook as JSON.
    Picklable, for a process pool."""
    from autograder.pipeline.execute import GradingExecute
    from autograder.pipeline.grading import course_config

    cwd = Path(course) / "submitted" / "student" / lab_id
    cwd.mkdir(parents=True, exist_ok=True)
    with setenv(NBGRADER_EXECUTION=GRADING):
        nb, _ = GradingExecute(config=course_config(Path(course))).preprocess(
            nbformat.reads(nb_json, as_version=4), {"metadata": {"path": str(cwd)}})
    return nbformat.writes(nb)

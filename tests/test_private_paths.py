"""`grade` and `release` warn when other users of the machine can read the course's private files
(issue 36: on a hub with Debian's 0755 home folders, a student read solutions/, source/ and the gradebook)."""

import os
import shutil
import tempfile
from pathlib import Path

import pytest

from autograder import private_paths


@pytest.fixture
def course():
    """A course root with its private folders and a gradebook, all readable by others, under folders that
    others may search (in /tmp itself: pytest's own temporary folders are closed to others)."""
    tmp_path = Path(tempfile.mkdtemp(prefix="kit-private-paths-", dir="/tmp"))
    root = tmp_path / "home" / "teacher" / "course"
    for name in ("solutions", "source"):
        (root / name).mkdir(parents=True)
        (root / name / "secret.py").write_text("answer = 42\n")
    (root / "gradebook.db").write_text("")
    for path in (tmp_path, tmp_path / "home", tmp_path / "home" / "teacher", root, root / "solutions", root / "source"):
        os.chmod(path, 0o755)
    os.chmod(root / "gradebook.db", 0o644)
    yield root
    shutil.rmtree(tmp_path)


def test_each_private_path_others_can_read_is_named_with_the_chmod_that_closes_it(course):
    exposed = private_paths.exposed(course, course)
    assert exposed == [course / "solutions", course / "source", course / "gradebook.db"]
    said = private_paths.warning(exposed)
    assert said.startswith("WARNING: OTHER USERS OF THIS MACHINE CAN READ") and f"chmod -R o-rwx {course / 'solutions'}" in said


def test_a_private_folder_or_a_closed_folder_above_keeps_them_in(course):
    os.chmod(course / "solutions", 0o750)
    os.chmod(course / "gradebook.db", 0o640)
    assert private_paths.exposed(course) == [course / "source"]
    os.chmod(course.parent, 0o700)  # the home folder closed to others: nothing below it can be reached
    assert private_paths.exposed(course, course) == []
    assert not private_paths.readable_by_others(course / "no-such-file")


def test_grade_and_release_print_the_warning(monkeypatch, capsys, course, tmp_path):
    from autograder.pipeline import grading

    monkeypatch.setattr(grading, "ROOT", course)
    monkeypatch.setattr(grading, "check_reference_available", lambda labs: None)
    monkeypatch.setattr(grading, "set_up", lambda *args: (_ for _ in ()).throw(SystemExit("stopped before grading")))
    class_dir = tmp_path / "class"
    class_dir.mkdir()
    with pytest.raises(SystemExit):
        grading.grade(class_dir, course)
    assert "WARNING: OTHER USERS OF THIS MACHINE CAN READ" in capsys.readouterr().out

    from autograder.release import notebooks

    monkeypatch.setattr(notebooks, "ROOT", course)
    monkeypatch.setattr(notebooks.nbgrader_apps, "generate_release", lambda labs: None)
    monkeypatch.setattr(notebooks, "raise_on_leaks", lambda tree: None)
    notebooks.release_all([])
    assert f"chmod -R o-rwx {course / 'solutions'}" in capsys.readouterr().out

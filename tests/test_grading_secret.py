"""The grading secret and each submission's seed (autograder/pipeline/grading_secret.py).

The seed covers everything the kernel can read of a submission: a submission that kept its
sources and changed the notebook's metadata, or a file beside it, which its code can read, gets
other cases (before, the seed covered the cells' sources only).
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

import nbformat

from autograder.catalogues import submissions
from autograder.hidden_tests import cases
from autograder.labs import Lab
from autograder.pipeline import grading_secret

LAB = Lab("train-kf")


def _folder(tmp_path, name: str, metadata: dict | None = None, extra: bytes | None = None):
    folder = tmp_path / name
    folder.mkdir()
    nb = submissions.solved(LAB)
    nb.metadata.update(metadata or {})
    nbformat.write(nb, folder / LAB.notebook_name)
    if extra is not None:
        (folder / "table.json").write_bytes(extra)
    return nb, folder


def test_the_secret_is_made_once_readable_by_its_owner_only(tmp_path, monkeypatch):
    path = tmp_path / "course" / ".grading-secret"
    monkeypatch.setenv(grading_secret.ENVIRONMENT_VARIABLE, str(path))
    first = grading_secret.secret()
    assert len(first) == grading_secret.SECRET_BYTES and grading_secret.secret() == first
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o600
    assert first.hex() not in grading_secret.fingerprint(first) and len(grading_secret.fingerprint(first)) == 16
    assert list(path.parent.iterdir()) == [path], "no temporary file is left behind"


def test_the_seed_covers_the_sources_the_notebook_file_and_the_files_beside_it(tmp_path):
    nb, folder = _folder(tmp_path, "first")
    same_nb, same_folder = _folder(tmp_path, "again")
    _, metadata = _folder(tmp_path, "metadata", metadata={"table": {"a": 1}})
    _, extra = _folder(tmp_path, "extra", extra=b'{"a": 1}')
    content = grading_secret.submission_content(nb, folder)
    assert grading_secret.submission_content(same_nb, same_folder) == content, "the same file regraded: the same seed"
    assert grading_secret.submission_content(nb, metadata) != content, "metadata the kernel can read"
    assert grading_secret.submission_content(nb, extra) != content, "a file the kernel can read"
    changed = submissions.solved(LAB)
    changed.cells[1].source += "\n# a comment"
    assert grading_secret.submission_content(changed, folder) != content


def test_another_secret_gives_another_seed():
    assert cases.seed_for(b"a" * 32, b"content") != cases.seed_for(b"b" * 32, b"content")
    assert cases.seed_for(b"a" * 32, b"content") == cases.seed_for(b"a" * 32, b"content")
    with cases.seeded(7):
        drawn = cases.rng(1104).standard_normal(3)
    with cases.seeded(8):
        assert not (cases.rng(1104).standard_normal(3) == drawn).any()
    assert cases.current_seed() == cases.DEFAULT_SEED


def test_the_kernel_gets_the_bytes_of_submitted_files_not_their_mode_or_times(tmp_path):
    """The seed covers a file's name and bytes, not its mode or times; so the kernel's copy has neither.
    The fourth adversarial review (stop 46) read two files' mode bits in the kernel under plain
    `nbgrader autograde`, with the same hidden cases before and after a chmod: room for answers to
    a submission's own cases (shutil.copy2 kept them). Fails on the code before."""
    from autograder.pipeline.execute import _scratch_copy

    folder = tmp_path / "submission"
    folder.mkdir()
    seen = {}
    for name, mode, when in (("a.txt", 0o600, 1_000_000_000), ("b.txt", 0o755, 1_200_000_000)):
        (folder / name).write_text("the same bytes\n")
        os.chmod(folder / name, mode)
        os.utime(folder / name, (when, when))
    with _scratch_copy({"metadata": {"path": str(folder)}}) as scratch:
        for name in ("a.txt", "b.txt"):
            copy = os.stat(os.path.join(scratch, name))
            assert Path(scratch, name).read_text() == "the same bytes\n"
            seen[name] = (stat.S_IMODE(copy.st_mode), copy.st_mtime)
    assert seen["a.txt"][0] == seen["b.txt"][0], "the two copies' modes differ as the submitted files' did"
    assert all(mtime > 1_300_000_000 for _, mtime in seen.values()), "a submitted file's time reached the kernel"

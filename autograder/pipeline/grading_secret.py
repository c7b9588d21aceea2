"""The course's grading secret, from which each submission's hidden cases are drawn.

Each submission's hidden cases come from its own seed (autograder/hidden_tests/cases.py):
HMAC-SHA256 of the submission's content (its cells' types and sources, after the sanitize step, and
every file in its folder, the submitted notebook included: everything its kernel can read of it)
under this secret. The same file regraded gets the same cases and the same score; a changed file
gets new cases; and without the secret, nobody can tell which cases a submission will get, so what
one submission learns about its cases (by printing what its function is called with into its
feedback) is no use to the next.

The secret is 32 random bytes in ``.grading-secret`` at the course root (git ignores it, and the
student bundle never holds it), made on the first grading; ``KIT_GRADING_SECRET_FILE`` names
another file (the same one for every machine of a sharded class, e.g. a mounted Kubernetes secret).
A grading kernel cannot read it: the sandbox lets a kernel read only the Python installation and
``course/``. Keep it with the gradebook: regrading a class with another secret gives every
submission other cases (a correct answer still passes, but a stochastic check's verdict on a
borderline answer may change). ``grades.versions.json`` records the secret's fingerprint, never
the secret.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from pathlib import Path

from nbformat import NotebookNode

from autograder.labs import ROOT

SECRET_FILE = ROOT / ".grading-secret"
"""The secret's default place."""
ENVIRONMENT_VARIABLE = "KIT_GRADING_SECRET_FILE"
SECRET_BYTES = 32


def secret_file() -> Path:
    """Where the secret is: ``KIT_GRADING_SECRET_FILE`` if set, else ``.grading-secret`` at the course root."""
    return Path(os.environ.get(ENVIRONMENT_VARIABLE) or SECRET_FILE)


def secret() -> bytes:
    """The course's secret, made (readable by its owner only) if there is none yet. Several grading
    processes that start at once all get the one that was made first."""
    path = secret_file()
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=path.parent, prefix=".grading-secret-", delete=False) as handle:
            handle.write(os.urandom(SECRET_BYTES))
        os.chmod(handle.name, 0o600)
        try:
            os.link(handle.name, path)  # atomic, and fails if another process made it first
        except FileExistsError:
            pass
        finally:
            os.unlink(handle.name)
    value = path.read_bytes()
    if len(value) < 16:
        raise ValueError(f"The grading secret {path} holds {len(value)} bytes; it needs at least 16. Remove it to "
                         "make a new one (every submission regraded then gets other hidden cases).")
    return value


def fingerprint(value: bytes) -> str:
    """A name for the secret that does not reveal it: 16 hex digits of a hash of it."""
    return hashlib.sha256(b"estimation-lab-kit grading secret\0" + value).hexdigest()[:16]


def submission_content(nb: NotebookNode, folder: str | os.PathLike | None = None) -> bytes:
    """What a submission's seed is computed from: everything its kernel can read of it. That is its
    cells' types and sources, in order, and the name and bytes of every file in ``folder`` (the
    kernel's working folder: the submitted notebook itself, whose metadata and outputs a cell could
    read, and any file submitted beside it). A submission that kept its sources and changed what
    they read would otherwise keep its cases."""
    digest = hashlib.sha256(json.dumps([[cell.cell_type, cell.source] for cell in nb.cells], ensure_ascii=False).encode())
    for path in sorted(Path(folder).iterdir()) if folder is not None else ():
        if path.is_file() and not path.is_symlink():
            digest.update(b"\0file\0" + path.name.encode(errors="surrogateescape") + b"\0")
            digest.update(hashlib.sha256(path.read_bytes()).digest())
    return digest.digest()

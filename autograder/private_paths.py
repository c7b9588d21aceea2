"""Which of the course's private files other users of this machine can read.

On a shared machine (a JupyterHub, a department server) the course root holds what students must never
see: ``solutions/`` (the reference and the hidden tests), ``source/`` (the model answers) and the
gradebook. Debian gives home folders mode 0755, so by default every local user can read them. ``grade``
and ``release`` print :func:`warning` when that is so; the kit cannot fix it for you, since the right
owner and group depend on how the machine is run.
"""

from __future__ import annotations

import stat
from pathlib import Path

from autograder.labs import ROOT

PRIVATE = ("solutions", "source", "gradebook.db")
"""The course root's private files and folders (a grading ``workdir`` has its own gradebook.db too)."""


def readable_by_others(path: Path) -> bool:
    """Whether a user who is neither ``path``'s owner nor in its group can read it: ``path`` grants read
    to others (and search, for a folder), and so does every folder above it (search). Access control
    lists are not read; a path that does not exist is not readable."""
    path = path.absolute()
    try:
        mode = path.stat().st_mode
        parents = [parent.stat().st_mode for parent in path.parents]
    except OSError:
        return False
    wanted = stat.S_IROTH | (stat.S_IXOTH if stat.S_ISDIR(mode) else 0)
    return (mode & wanted) == wanted and all(parent & stat.S_IXOTH for parent in parents)


def exposed(root: Path = ROOT, workdir: Path | None = None) -> list[Path]:
    """The private paths of the course ``root`` (and the gradebook of ``workdir``) that others can read."""
    paths = [root / name for name in PRIVATE] + ([workdir / "gradebook.db"] if workdir is not None else [])
    return [path for path in dict.fromkeys(paths) if readable_by_others(path)]


def warning(paths: list[Path]) -> str:
    """What ``grade`` and ``release`` print when ``paths`` (from :func:`exposed`) is not empty."""
    listed = "\n".join(f"  {path}" for path in paths)
    return (f"WARNING: OTHER USERS OF THIS MACHINE CAN READ THE COURSE'S PRIVATE FILES:\n{listed}\n"
            "On a machine that students log in to (a JupyterHub), they can read the model answers and the hidden "
            "tests there. Take read and search away from others, for example `chmod -R o-rwx "
            + " ".join(str(path) for path in paths) + "` (README: Running a course on a shared machine).")

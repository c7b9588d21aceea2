"""Remove a folder that a kernel could write in, however deep the kernel made it.

Python 3.11's ``shutil.rmtree`` recurses once per level, and ``ignore_errors=True`` does not cover
the RecursionError it raises on a tree deeper than Python's recursion limit: a kernel that nested 3,000
folders in its working or private folder (by ``chdir``, past PATH_MAX) left the whole folder on the
disk, another copy at each regrade, and its submission was not graded (adversarial review). coreutils'
``rm`` walks a tree of any depth with directory descriptors, so the kit removes such folders with it.
"""

from __future__ import annotations

import os
import subprocess


def remove_tree(path: str | os.PathLike) -> None:
    """Remove ``path`` and everything beneath it, of any depth, without following links out of it or
    crossing into another file system; nothing is raised if it is gone already or cannot be removed."""
    subprocess.run(["rm", "-rf", "--one-file-system", "--", os.fspath(path)], stdin=subprocess.DEVNULL,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)

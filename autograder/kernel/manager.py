"""The grading kernel's manager: a Jupyter kernel started in the sandbox (autograder/kernel/sandbox.py).

``SandboxedKernelManager`` is the kernel manager class for nbclient (``kernel_manager_class``). It
chooses what a kernel may read and write, gives each kernel a private folder, and puts the
sandbox's launcher in front of the kernel's command.
"""

from __future__ import annotations

import atexit
import itertools
import os
import shutil
import site
import subprocess
import sys
import tempfile
import weakref
from functools import cache
from pathlib import Path
from typing import Any

import zmq
import zmq.asyncio
from jupyter_client.asynchronous import AsyncKernelClient
from jupyter_client.manager import AsyncKernelManager
from traitlets import CaselessStrEnum, Integer, List, Type, Unicode

from autograder.labs import ROOT
from autograder.kernel.remove_tree import remove_tree
from autograder.kernel.sandbox import KERNEL_UIDS_FROM, launcher_command, wanted_layers

PRIVATE_PARENT = "/tmp"
_KERNELS_STARTED = itertools.count()
"""How many kernel managers of this process have made a private folder (for their kernels' user IDs)."""
"""Where each kernel's private folder is made: a short path, since a Unix socket's path is at most 107 bytes."""


def python_read_paths() -> list[str]:
    """The Python installation this process runs on: its environment and base installation, the
    interpreter's real path, site-packages, and every ``sys.path`` entry inside the environment
    (each may be a link to elsewhere, which is what gets allowed)."""
    prefixes = (sys.prefix, sys.base_prefix)
    inside = [p for p in sys.path if p and any(_is_beneath(p, prefix) for prefix in prefixes)]
    return _unique([*prefixes, os.path.realpath(sys.executable), *site.getsitepackages(), *inside])


SYSTEM_READ_PATHS = (
    "/usr/lib", "/lib", "/lib64",        # the C library and other shared libraries, the dynamic loader
    "/etc/ld.so.cache", "/etc/ld.so.conf", "/etc/ld.so.conf.d",  # how the loader finds them
    "/etc/localtime", "/etc/timezone",   # the local time zone
    "/etc/locale.alias",                 # locale names (gettext)
    "/etc/ssl/openssl.cnf",              # OpenSSL's settings, read when hashlib starts it
    "/etc/fonts",                        # fontconfig
    "/etc/passwd", "/etc/group", "/etc/nsswitch.conf",  # user names (getpass, pathlib.home)
    "/etc/mime.types",                   # mimetypes
    "/usr/share",                        # fonts, time zones
    "/dev/urandom",
    "/proc/self",                        # this process only
    "/sys/devices/system/cpu",           # how many cores (NumPy, os.cpu_count)
)
"""The system's files every kernel may read. Of /etc, only what Python and its libraries read: a
kernel run by root could otherwise print /etc/shadow into a feedback page."""
SYSTEM_WRITE_PATHS = ("/dev/null",)
"""The system's files every kernel may write."""


@cache
def course_site() -> str:
    """A folder that holds only ``course``, a link to this course root's ``course/``: the grading
    kernel's PYTHONPATH, so that it imports the course package of the root being graded, whichever
    checkout the environment's ``-e .`` points at (issue 32: kernels graded with another checkout's
    ``course``), and reads nothing else of the root. Made once per process, under /tmp, and
    removed when the process exits."""
    site = Path(tempfile.mkdtemp(prefix="kit-course-", dir=PRIVATE_PARENT))
    (site / "course").symlink_to(ROOT / "course", target_is_directory=True)
    atexit.register(remove_tree, site)
    return str(site)


@cache
def font_cache(read: tuple[str, ...]) -> Path | None:
    """Matplotlib's list of fonts as a kernel that reads only beneath ``read`` sees them, made once
    per process by Matplotlib in the sandbox and copied into each kernel's MPLCONFIGDIR, which saves
    every kernel a second (never taken from a kernel, which could tamper with it); None when it
    could not be made."""
    folder = tempfile.mkdtemp(prefix="kit-fonts-", dir=PRIVATE_PARENT)
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    command = launcher_command(list(read), [folder, *SYSTEM_WRITE_PATHS], wanted_layers())
    subprocess.run([*command, sys.executable, "-c", "import matplotlib.font_manager"], cwd=folder,
                   env={**os.environ, "MPLCONFIGDIR": folder, "HOME": folder, "TMPDIR": folder},
                   capture_output=True, timeout=300, check=False)
    return next(Path(folder).glob("fontlist-*.json"), None)


class CappedKernelClient(AsyncKernelClient):
    """jupyter_client's client, whose sockets take no message larger than its kernel manager's
    ``max_message_bytes``."""

    def _context_default(self) -> zmq.asyncio.Context:
        context = super()._context_default()
        context.setsockopt(zmq.MAXMSGSIZE, self.parent.max_message_bytes)
        return context


class SandboxedKernelManager(AsyncKernelManager):
    """A Jupyter kernel manager whose kernels run in the sandbox (see the module doc).

    The kernel talks over Unix sockets (``ipc``: TCP on loopback does not cross the network
    namespace) in a private folder made for each kernel, ``private_folder``, which also holds its
    TMPDIR, HOME, IPYTHONDIR, MPLCONFIGDIR and Jupyter runtime files, and which is removed when the
    kernel shuts down. The kernel may read the Python installation, the system's shared files
    (``SYSTEM_READ_PATHS``), the course's ``course/`` package (which it imports through ``course_site``), and
    ``read_paths``; it may write in
    its working directory (the submission's folder, the ``cwd`` it is started with; the private
    folder when none is given), the private folder, ``SYSTEM_WRITE_PATHS`` and ``write_paths``.
    A path that holds the course root is refused: the kernel does not start.
    """

    transport = CaselessStrEnum(["ipc"], default_value="ipc", config=True,
                                help="Unix sockets only: TCP does not reach into the kernel's network namespace.")
    client_factory = Type(CappedKernelClient, klass=AsyncKernelClient, config=True,
                          help="The kernel client: jupyter_client's, taking no message larger than max_message_bytes.")
    max_message_bytes = Integer(128 * 2**20, config=True, help=(
        "The largest message (ZeroMQ frame) the grader takes from a kernel. ZeroMQ refuses a larger one before "
        "the grader reads it, and the kernel's output stops reaching the grader, so the cell times out. Without "
        "the cap one message of a gigabyte (the kernel's memory cap allows that) made the grader hold several times "
        "its size while it decoded it; a cell keeps 1,000,000 characters of output anyway."))
    read_paths = List(Unicode(), help="Further paths the kernel may read beneath.").tag(config=True)
    write_paths = List(Unicode(), help="Further paths the kernel may read and write beneath.").tag(config=True)

    _private: Path | None = None
    _uid: int | None = None

    @property
    def private_folder(self) -> Path | None:
        """This kernel's private folder (None before the kernel is started): short, under /tmp,
        writable by the kernel, removed at shutdown."""
        return self._private

    def kernel_read_paths(self) -> list[str]:
        """Every path the kernel may read beneath: the defaults that exist here, and ``read_paths``."""
        defaults = [*python_read_paths(), *SYSTEM_READ_PATHS, str(ROOT / "course"), course_site()]
        return _unique([*(p for p in defaults if p and os.path.exists(p)), *self.read_paths])

    def kernel_write_paths(self, cwd: str) -> list[str]:
        """Every path the kernel may write beneath: its working directory ``cwd``, its private
        folder, ``SYSTEM_WRITE_PATHS`` and ``write_paths``."""
        return _unique([cwd, str(self._private), *SYSTEM_WRITE_PATHS, *self.write_paths])

    def _make_private_folder(self) -> Path:
        """A new private folder with its subfolders, the connection file and ipc sockets placed in it."""
        private = Path(tempfile.mkdtemp(prefix="kit-", dir=PRIVATE_PARENT))
        for name in ("tmp", "home", "ipython", "matplotlib", "runtime"):
            (private / name).mkdir()
        # IPython's profile, made here as IPython would make it: the kernel may not chmod (sandbox.ATTRIBUTE_CALLS),
        # and IPython copies a README into a startup folder it has just made with shutil.copy, which does
        profile = private / "ipython" / "profile_default"
        for name in ("startup", "log", "security", "pid"):
            (profile / name).mkdir(mode=0o700, parents=True)
        (profile / "startup" / "README").touch()
        weakref.finalize(self, remove_tree, private)
        # when root grades, the kernel's own user ID, the same after a restart (its files stay its own), and
        # no other live manager's: this process's ID (below 2**22) and a count of its managers, modulo 256
        self._uid = KERNEL_UIDS_FROM + (os.getpid() % 2**22 << 8) + next(_KERNELS_STARTED) % 256
        self.connection_file = str(private / "kernel.json")
        self.ip = str(private / "ipc")
        return private

    async def _async_pre_start_kernel(self, **kw: Any) -> tuple[list[str], dict[str, Any]]:
        """jupyter_client's preparation, then the launcher in front of the kernel's command and the
        private folder in its environment; returns the command and the launch arguments."""
        read = self.kernel_read_paths()
        _refuse_course_root([*read, *self.write_paths, *([kw["cwd"]] if kw.get("cwd") else [])])
        if self._private is None:  # a restart keeps the folder and the connection file
            self._private = self._make_private_folder()
        kw["cwd"] = str(Path(kw.get("cwd") or self._private).resolve())
        write = self.kernel_write_paths(kw["cwd"])
        fonts = font_cache(tuple(read))
        if fonts is not None:
            shutil.copy(fonts, self._private / "matplotlib")
        kernel_cmd, kw = await super()._async_pre_start_kernel(**kw)
        # the grader's environment may hold secrets (GRADEBOOK_URL with a password, PGPASSWORD, the
        # grading secret's file): the kernel gets only what a Python program needs to run alike
        # everywhere, and a PYTHONPATH of this root's `course` alone (nothing else of the root)
        kw["env"] = kernel_environment(kw["env"])
        kw["env"].update(
            PYTHONPATH=course_site(),
            TMPDIR=str(self._private / "tmp"),
            HOME=str(self._private / "home"),
            IPYTHONDIR=str(self._private / "ipython"),
            MPLCONFIGDIR=str(self._private / "matplotlib"),
            JUPYTER_RUNTIME_DIR=str(self._private / "runtime"),
        )
        # the kernel's own file descriptors 0-2 go nowhere: inherited, they were the grader's terminal and
        # log, which a kernel could read typeahead from, truncate, flood or write escape codes to (what a
        # kernel prints reaches the notebook through its messages, not through these)
        kw.update(stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        own = [str(self._private), kw["cwd"]]  # closed to other kernels when root grades (sandbox.confine)
        return [*launcher_command(read, write, wanted_layers(), own, self._uid), *kernel_cmd], kw

    async def _async_shutdown_kernel(self, now: bool = False, restart: bool = False) -> None:
        """Stop the kernel at once (SIGKILL to its process group), whatever ``now`` says: it has
        nothing to save, and its graceful shutdown looks for its child processes in /proc, which it
        may not read, and logs the failure."""
        await super()._async_shutdown_kernel(now=True, restart=restart)

    shutdown_kernel = _async_shutdown_kernel

    async def _async_cleanup_resources(self, restart: bool = False) -> None:
        """jupyter_client's clean-up, and the private folder removed unless the kernel restarts."""
        await super()._async_cleanup_resources(restart=restart)
        if not restart and self._private is not None:
            remove_tree(self._private)  # the kernel wrote in it: of any depth
            self._private = None


KERNEL_ENVIRONMENT = ("PATH", "LANG", "LANGUAGE", "TZ", "NBGRADER_EXECUTION", "JPY_PARENT_PID",
                      "PYDEVD_DISABLE_FILE_VALIDATION", "SOURCE_DATE_EPOCH")
"""The variables of the grader's environment that a grading kernel gets, with those that begin with
``KERNEL_ENVIRONMENT_PREFIXES``: the locale, the time zone, whether nbgrader is grading (course.checks
reads it), and the numerical libraries' settings (threads, and OpenBLAS's core type, which some
machines need to compute right)."""
KERNEL_ENVIRONMENT_PREFIXES = ("LC_", "OPENBLAS_", "OMP_", "MKL_", "NUMEXPR_", "VECLIB_")


def kernel_environment(environment: dict[str, str]) -> dict[str, str]:
    """The part of ``environment`` that a grading kernel is started with (``KERNEL_ENVIRONMENT``)."""
    return {name: value for name, value in environment.items()
            if name in KERNEL_ENVIRONMENT or name.startswith(KERNEL_ENVIRONMENT_PREFIXES)}


def _refuse_course_root(paths: list[str]) -> None:
    """Raise a ValueError if one of ``paths`` is the course root or holds it: the kernel could then
    read the reference, the gradebook and every student's work."""
    root = os.path.realpath(ROOT)
    for path in paths:
        if _is_beneath(root, os.path.realpath(path)):
            raise ValueError(f"The grading kernel would be allowed {path}, which holds the course root {root} "
                             "(the reference, the gradebook, every student's work). Start it in the "
                             "submission's own folder, and allow no folder that holds the course root.")


def _is_beneath(path: str, folder: str) -> bool:
    """Whether ``path`` is ``folder`` or inside it, by their absolute paths."""
    path, folder = os.path.abspath(path), os.path.abspath(folder)
    return path == folder or path.startswith(folder.rstrip(os.sep) + os.sep)


def _unique(paths: list[str]) -> list[str]:
    """``paths`` without repeats, in order."""
    return list(dict.fromkeys(paths))


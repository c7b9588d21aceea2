"""A sandbox for the grading kernel: what it may read and write, and no network.

Two layers of the Linux kernel confine the kernel process, applied by a launcher that then
``exec``s the kernel (in a grandchild, when it makes a PID namespace):

- files: a Landlock ruleset (``landlockpy``) lets the process read only beneath the read paths
  and read and write only beneath the write paths; everything else on the filesystem is closed,
  even to root. It also keeps the process from signalling or tracing processes outside it. Landlock
  does not control a file's mode, owner, times or extended attributes: a seccomp filter
  (``pyseccomp``, over the system's libseccomp) refuses every call that changes them;
- network: a private network namespace, whose only interface is a loopback that is down. The
  process also gets its own user namespace where the OS allows one, so that a kernel started by
  root holds no capability over the machine (loading kernel modules, mounting, raw devices), and
  its own PID namespace, under an init that ends when the kernel ends: Linux then kills every
  process left in the namespace, so nothing the kernel starts (a daemon that left its process
  group, a fork bomb) outlives it, and its own IPC namespace, so that no System V shared memory
  or message queue does either. The launcher stays, as the kernel's manager's process, and waits.
  The kernel may have at most MAX_TASKS processes and threads. Linux exempts root from that cap, so
  a kernel started by root runs as a user of its own (``--uid``), which is root in the kernel's
  user namespace and no one outside it.

``python -m autograder.kernel.sandbox --read P ... --write P ... -- CMD ARGS...`` is the launcher. It never
refuses: a layer the OS does not offer is left out, and it says so on stderr. ``status()`` says what
this OS offers, in a sentence for the grader's output. ``SandboxedKernelManager``
(autograder/kernel/manager.py, which imports this module, never the other way) starts Jupyter kernels
through the launcher. The launcher imports only the standard library, ``landlockpy`` and ``pyseccomp``: it
runs at every kernel start, and importing jupyter_client would add a third of a second to each.

The environment variable ``KIT_SANDBOX`` turns layers off: ``off`` (none), or the layers to keep,
``files`` or ``network``. Unset, or ``on``: both.
"""

from __future__ import annotations

import argparse
import contextlib
import ctypes
import errno
import os
import re
import resource
import select
import shutil
import signal
import sys
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import NoReturn

import landlockpy
from landlockpy import AccessFS, Scope

SWITCH = "KIT_SANDBOX"
LAYERS = ("files", "network")

CLONE_NEWIPC = 0x08000000
CLONE_NEWNET = 0x40000000
CLONE_NEWPID = 0x20000000
CLONE_NEWUSER = 0x10000000
PR_SET_NO_NEW_PRIVS = 38
PR_CAPBSET_DROP = 24
CLONE_NEWNS = 0x00020000
MS_REMOUNT, MS_NOATIME, MS_BIND, MS_REC, MS_PRIVATE = 32, 1024, 4096, 16384, 1 << 18
MAX_TASKS = 256
"""The most processes and threads that a kernel may have at once (RLIMIT_NPROC, which Linux counts
per user namespace, so per kernel here): a fork bomb stops there. Linux exempts root's user ID from
the limit, so a kernel started by root runs as a user of its own (``kernel_uid``)."""
KERNEL_UIDS_FROM = 2**30
"""The user IDs of kernels started by root are ``KERNEL_UIDS_FROM`` and above (below 2**31): IDs that
name no account, so that no file outside a kernel's own folders belongs to one."""

ATTRIBUTE_CALLS = ("chmod", "fchmod", "fchmodat", "fchmodat2", "chown", "fchown", "lchown", "fchownat",
                   "utime", "utimes", "futimesat", "utimensat", "setxattr", "lsetxattr", "fsetxattr",
                   "removexattr", "lremovexattr", "fremovexattr", "truncate")
"""The system calls that change a file's mode, owner, times or extended attributes, and ``truncate``
by path. Landlock controls none of the first (and truncation only from ABI 3, Linux 6.2), so a kernel
could use them on any file it can name that it owns, or, started by root, on which its capabilities
hold (root's files): make ``solutions/`` readable by every user, make /etc/shadow readable, or lock
the grader out of its own code. A seccomp filter makes each fail with EPERM."""
RING_AND_WATCH_CALLS = ("io_uring_setup", "io_uring_enter", "io_uring_register", "inotify_init", "inotify_init1",
                        "inotify_add_watch", "fanotify_init", "fanotify_mark", "mincore", "cachestat", "fadvise64",
                        "readahead")
"""io_uring, whose operations (an xattr set among them) are not system calls, so that the filter never
sees them: a re-attack set an xattr through it, and wrote ACLs on the grader's own files; inotify and
fanotify, which Landlock does not control: a kernel watched folders it may not read, and saw every
other kernel's private folder made in /tmp; and the page cache's state, which a kernel emptied of a
file it may read (fadvise) and another read back (mincore): a channel between kernels. The seccomp
filter refuses them (EPERM)."""
ARGUMENT_RULES = {
    "ioctl": [(1, 0x40086602), (1, 0x40046602), (1, 0x401C5820)],  # FS_IOC_SETFLAGS (64, 32 bit), FS_IOC_FSSETXATTR
    "fcntl": [(1, 1026)],  # F_NOTIFY: dnotify, which saw another kernel's reads
}
"""Calls refused with one argument's value, (argument's index, value): a file's flags (chattr: the
grader's own files took bits from one kernel for a later one) and dnotify."""
NAMESPACE_CALLS = ("unshare", "setns", "mount", "umount2", "pivot_root", "open_tree", "move_mount", "fsopen", "fsconfig",
                   "fsmount", "fspick", "mount_setattr")
"""Making namespaces and mounts, which a kernel never needs (the launcher makes its namespaces before
the filter is loaded): each new mount namespace moves a counter that every process of the machine
reads (the unique mount ID of statx, Linux 6.8), and a fourth review passed 99% of raw bits through
it between two kernels graded side by side, 125 bits a second. ``clone`` with a namespace's flag is
refused too (``NAMESPACE_FLAGS``), and ``clone3``, whose flags the filter cannot read, answers ENOSYS,
so that the C library falls back to ``clone`` (as container runtimes do)."""
NAMESPACE_FLAGS = (0x00020000, 0x02000000, 0x04000000, 0x08000000, 0x10000000, 0x20000000, 0x40000000)
"""CLONE_NEWNS, NEWCGROUP, NEWUTS, NEWIPC, NEWUSER, NEWPID, NEWNET: ``clone`` with any of them is refused."""
IDENTITY_CALLS = ("setuid", "setgid", "setreuid", "setregid", "setresuid", "setresgid", "setfsuid", "setfsgid",
                  "setgroups", "add_key", "request_key", "keyctl")
"""The system calls that change who a process is, and the kernel's keyrings. Started by root, the
kernel is root in its user namespace, where user 1 is root outside: ``setresuid(1)`` made it root
again, free of the cap on processes. A keyring belongs to a user and outlives the kernel, so it would
carry data from one submission's kernel to the next. The seccomp filter makes each fail with EPERM."""
KEPT_CAPABILITIES = (1, 2)
"""CAP_DAC_OVERRIDE and CAP_DAC_READ_SEARCH: the only capabilities the kernel keeps in its user
namespace (the rest leave its bounding set), so that, started by root, it still reads the Python
installation in a folder closed to others, where Landlock allows."""
NEWER_CALLS = {0xC000003E: (457, 458, 463, 466, 467, 469), 0xC00000B7: (457, 458, 463, 466, 467, 469)}
"""statmount and listmount (Linux 6.8), setxattrat and removexattrat (6.13), open_tree_attr (6.15)
and file_setattr (6.17), by number on x86-64 and arm64 (AUDIT_ARCH values), where libseccomp may
not know their names yet."""

READ = AccessFS.READ_FILE | AccessFS.READ_DIR | AccessFS.EXECUTE
"""What a read path allows: read files and list folders, run programs."""
NOT_WRITABLE = AccessFS.MAKE_CHAR | AccessFS.MAKE_BLOCK | AccessFS.IOCTL_DEV
"""Rights a write path does not give: device nodes (root could make one for a raw disk) and ioctls on devices."""
ON_FILES = AccessFS.EXECUTE | AccessFS.WRITE_FILE | AccessFS.READ_FILE | AccessFS.TRUNCATE | AccessFS.IOCTL_DEV
"""The rights Landlock accepts on a rule for a single file (the others are for folders)."""


@dataclass(frozen=True)
class SandboxStatus:
    """What this OS offers the sandbox, and which layers a kernel started now gets."""

    landlock_abi: int
    """The Landlock ABI version of the running Linux kernel; 0 when there is none."""
    network_namespace: bool
    """Whether this process can make a new network namespace."""
    files: bool
    """Whether kernels get the files layer (Landlock), given the OS and ``KIT_SANDBOX``."""
    network: bool
    """Whether kernels get the network layer (private network and PID namespaces)."""
    summary: str
    """One line for the grader's output and the grades record."""

    @property
    def complete(self) -> bool:
        """True when kernels get both layers."""
        return self.files and self.network


def wanted_layers() -> tuple[str, ...]:
    """The layers ``KIT_SANDBOX`` asks for (both when unset or ``on``, none when ``off``); a
    ValueError for any other word than a layer's name."""
    value = os.environ.get(SWITCH, "on").strip().lower()
    if value in ("", "on"):
        return LAYERS
    if value == "off":
        return ()
    named = tuple(word.strip() for word in value.split(","))
    unknown = [word for word in named if word not in LAYERS]
    if unknown:
        raise ValueError(f"{SWITCH}={value!r}: it is 'on', 'off', or the layers to keep among {', '.join(LAYERS)}.")
    return tuple(layer for layer in LAYERS if layer in named)


def status() -> SandboxStatus:
    """What this OS offers (Landlock's ABI version, whether a network namespace can be made), which
    layers kernels get given ``KIT_SANDBOX``, and a one-line summary in plain English."""
    abi = landlock_abi()
    netns_problem = network_namespace_problem()
    wanted = wanted_layers()
    filter_problem = attribute_filter_problem()
    files = abi > 0 and filter_problem is None and "files" in wanted
    network = netns_problem is None and "network" in wanted
    if "files" not in wanted:
        files_part = f"Landlock turned off ({SWITCH}={os.environ.get(SWITCH)})"
    elif abi == 0:
        files_part = ("Landlock unavailable (the Linux kernel lacks it or does not enable it, or a container "
                      "forbids it: it needs Linux 5.13 or later with landlock among its lsm= boot options)")
    elif filter_problem is not None:
        files_part = (f"Landlock ABI {abi} (files) but no seccomp filter ({filter_problem}), so the kernel can "
                      "change the mode, owner and times of files it can name")
    else:
        files_part = f"Landlock ABI {abi} and a seccomp filter (files)"
    if "network" not in wanted:
        network_part = f"network namespace turned off ({SWITCH}={os.environ.get(SWITCH)})"
    elif netns_problem is not None:
        network_part = f"no network namespace ({netns_problem})"
    elif not processes_capped():
        network_part = ("private network and PID namespaces (no network, and no process outlives the kernel; "
                        "as root's, its processes are not capped)")
    else:
        network_part = (f"private network and PID namespaces (no network, no process outlives the kernel, and at "
                        f"most {MAX_TASKS} processes in it)")
    if files and network:
        summary = f"{files_part} and {network_part}"
    elif files or network:
        summary = (f"PARTLY SANDBOXED: {files_part} and {network_part}: the grading kernel can "
                   + ("use the network" if files else "read every file the grader's user can"))
    else:
        summary = (f"NOT SANDBOXED: {files_part}, and {network_part}: the grading kernel can read every "
                   "file the grader's user can, and use the network")
    return SandboxStatus(abi, netns_problem is None, files, network, summary)


def landlock_abi() -> int:
    """The Landlock ABI version of the running kernel (``landlock_create_ruleset(NULL, 0,
    LANDLOCK_CREATE_RULESET_VERSION)``); 0 when Landlock is unavailable."""
    try:
        return landlockpy.abi_version()
    except OSError:  # refused otherwise than by a kernel without Landlock: a container's seccomp filter
        return 0


@cache
def attribute_filter_problem() -> str | None:
    """None when ``forbid_attribute_changes`` works here (tried in a child process, which exits);
    otherwise why not, in words."""
    if sys.platform != "linux":
        return "seccomp is a Linux feature"
    pid = os.fork()
    if pid == 0:
        try:
            set_no_new_privs()
            forbid_attribute_changes()
        except RuntimeError:  # pyseccomp's word for a missing libseccomp
            os._exit(100)
        except OSError:
            os._exit(101)
        os._exit(0)
    code = os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1])
    if code == 0:
        return None
    return "libseccomp is not installed" if code == 100 else "the OS refused it"


@cache
def processes_capped() -> bool:
    """Whether a kernel started here gets the MAX_TASKS cap on its processes: True for a plain user,
    and for root when its kernels can run as a user of their own (tried in a child process, which
    enters the namespaces and exits)."""
    if os.getuid() != 0:
        return True
    if sys.platform != "linux":
        return False
    pid = os.fork()
    if pid == 0:
        try:
            enter_network_namespace()
            outside = Path("/proc/self/uid_map").read_text().split()[1:2]  # "0 <uid outside> 1"
        except OSError:
            os._exit(1)
        os._exit(0 if outside not in ([], ["0"]) else 1)
    _, wait_status = os.waitpid(pid, 0)
    return os.waitstatus_to_exitcode(wait_status) == 0


@cache
def network_namespace_problem() -> str | None:
    """None when this process can make a new network namespace (tried in a child process, which
    exits); otherwise why not, in words."""
    if sys.platform != "linux":
        return "network namespaces are a Linux feature"
    pid = os.fork()
    if pid == 0:  # the child: try, and say how it went in its exit status
        try:
            enter_network_namespace()
        except OSError as error:
            os._exit(error.errno or 255)
        os._exit(0)
    _, wait_status = os.waitpid(pid, 0)
    code = os.waitstatus_to_exitcode(wait_status)
    return None if code == 0 else _namespace_error(code)


def _namespace_error(code: int) -> str:
    """Why a namespace could not be made, from the errno of the failed call."""
    if code == errno.EPERM:
        return ("namespaces are not allowed here: user namespaces are disabled for this user, or a "
                "container forbids them")
    if code == errno.ENOSPC:
        return "the limit of user namespaces is reached (sysctl user.max_user_namespaces)"
    if code == errno.EINVAL:
        return "this Linux kernel was built without network or user namespaces"
    return f"unshare failed: {os.strerror(code)}"


@cache
def _libc() -> ctypes.CDLL:
    """The C library, for unshare and prctl (Python 3.11's os has neither)."""
    return ctypes.CDLL(None, use_errno=True)


def _check(result: int, call: str) -> None:
    """Raise the OSError for a libc call that returned -1."""
    if result == -1:
        code = ctypes.get_errno()
        raise OSError(code, f"{call}: {os.strerror(code)}")


def enter_network_namespace(uid: int | None = None) -> None:
    """Move this process into new network and IPC namespaces (System V shared memory, semaphores and
    message queues, which would outlive the kernel and be shared with other kernels, die with the
    last process in it), and the children it starts from now on into a new PID namespace. First into
    a new user namespace, where the OS allows one: a plain user is itself there; root becomes
    ``kernel_uid(uid)``, which is root inside and holds no capability over the machine. Without the
    uid map, which some systems refuse, the process shows as nobody and still works. Raises
    OSError when the namespaces cannot be made."""
    if os.getuid() == 0:
        _enter_user_namespace_as(kernel_uid(uid))
    elif _libc().unshare(CLONE_NEWUSER) == 0:
        _map_own_ids()
    _check(_libc().unshare(CLONE_NEWNET | CLONE_NEWPID | CLONE_NEWIPC), "unshare(CLONE_NEWNET | CLONE_NEWPID | CLONE_NEWIPC)")


def kernel_uid(chosen: int | None = None) -> int:
    """The user a kernel started by root runs as, outside its user namespace: ``chosen`` (the
    launcher's ``--uid``, which a kernel manager keeps for its kernel's restarts), or else
    ``KERNEL_UIDS_FROM`` plus this process's ID, which no other running launcher has."""
    return chosen if chosen is not None else KERNEL_UIDS_FROM + os.getpid()


def _map_own_ids() -> None:
    """In a user namespace just made: be there who this process is outside (when the OS allows it)."""
    uid, gid = os.geteuid(), os.getegid()
    with contextlib.suppress(OSError):
        Path("/proc/self/setgroups").write_text("deny")
        Path("/proc/self/uid_map").write_text(f"{uid} {uid} 1")
        Path("/proc/self/gid_map").write_text(f"{gid} {gid} 1")


def _enter_user_namespace_as(uid: int) -> None:
    """Run by root: enter a new user namespace and become ``uid`` (user and group), which is root
    inside it. Root outside is mapped too (as user 1), so that the capabilities the process holds
    inside still reach root's files, as they did: the kernel reads a Python installation in /root,
    and Landlock, not ownership, decides what it may touch. But Linux counts its processes against
    RLIMIT_NPROC, as it does not root's, and it can signal no process of root's. Only a process
    outside the namespace may write such a map: a helper child writes it, once this process has
    entered. Where that fails, this process maps root to itself as a plain user would."""
    ready, go = os.pipe()
    helper = os.fork()
    if helper == 0:  # the helper: wait for the namespace, then map it
        os.close(go)
        entered = os.read(ready, 1) == b"y"
        parent, mapping = os.getppid(), f"0 {uid} 1\n1 0 1\n"
        try:
            if entered:
                Path(f"/proc/{parent}/uid_map").write_text(mapping)
                Path(f"/proc/{parent}/gid_map").write_text(mapping)
        except OSError:
            os._exit(1)
        os._exit(0 if entered else 1)
    os.close(ready)
    entered = _libc().unshare(CLONE_NEWUSER) == 0
    os.write(go, b"y" if entered else b"n")
    os.close(go)
    mapped = os.waitstatus_to_exitcode(os.waitpid(helper, 0)[1]) == 0
    if mapped:
        os.setgroups([])
        os.setresgid(0, 0, 0)
        os.setresuid(0, 0, 0)
    elif entered:
        _map_own_ids()


def run_below_namespace_init() -> None:
    """After ``enter_network_namespace``: fork twice and return in the grandchild, whose parent is
    the init (PID 1) of the new PID namespace. The init reaps every orphan of the namespace and
    exits with the grandchild's status when it ends; Linux then kills every process left in the
    namespace. This process, the launcher, exits with the init's status, and kills the init if its
    own parent (the grader) dies first: ipykernel's own check that its parent lives cannot see the
    grader from inside the namespace, so the grandchild's JPY_PARENT_PID names its real parent, the
    init (PID 1), which ipykernel does not watch."""
    init = os.fork()
    if init:
        parent = os.getppid()
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # the grader's interrupts are for the kernel
        ended = os.pidfd_open(init)
        while not select.select([ended], [], [], 1.0)[0]:
            if os.getppid() != parent:
                os.kill(init, signal.SIGKILL)
        _exit_as(os.waitpid(init, 0)[1])
    kernel = os.fork()
    if kernel:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        while True:
            pid, status = os.wait()
            if pid == kernel:
                _exit_as(status)
    if "JPY_PARENT_PID" in os.environ:
        os.environ["JPY_PARENT_PID"] = "1"


def _exit_as(status: int) -> NoReturn:
    """Exit with the status a child ended with (128 + the signal's number if a signal ended it)."""
    code = os.waitstatus_to_exitcode(status)
    os._exit(code if code >= 0 else 128 - code)


def set_no_new_privs() -> None:
    """Make this process and its children unable to gain privileges (setuid programs, file
    capabilities); raises OSError if the OS refuses."""
    _check(_libc().prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0), "prctl(PR_SET_NO_NEW_PRIVS)")


def restrict_files(read: list[str], write: list[str]) -> list[str]:
    """Apply a Landlock ruleset to this process: it may read (files, folders, execute) only beneath
    ``read`` and read, write, create and remove only beneath ``write``; signals and abstract Unix
    sockets stay inside. Rights the running ABI lacks are left out. Returns the paths that could not
    be allowed, each with the reason (they stay closed); raises OSError when Landlock is unavailable
    or refuses the ruleset."""
    skipped = []
    with landlockpy.Ruleset(handled_fs=landlockpy.fs_for_abi(landlockpy.abi_version()),
                            handled_net=landlockpy.AccessNet.NONE,
                            scoped=Scope.SIGNAL | Scope.ABSTRACT_UNIX_SOCKET) as ruleset:
        for paths, access in ((read, READ), (write, ruleset.handled_fs & ~NOT_WRITABLE)):
            for path in paths:
                try:
                    ruleset.allow_path(path, access if os.path.isdir(path) else access & ON_FILES)
                except OSError as error:
                    skipped.append(f"{path} ({error.strerror})")
        ruleset.restrict(no_new_privs=True)
    return skipped


def drop_capabilities() -> None:
    """Remove every capability but ``KEPT_CAPABILITIES`` from this process's bounding set, so that the
    program it runs next holds no other (it needs CAP_SETPCAP, which root has in its namespace; a
    capability this Linux does not know is skipped)."""
    last = int(Path("/proc/sys/kernel/cap_last_cap").read_text())
    for capability in range(last + 1):
        if capability not in KEPT_CAPABILITIES:
            _check(_libc().prctl(PR_CAPBSET_DROP, capability, 0, 0, 0), "prctl(PR_CAPBSET_DROP)")


def forbid_attribute_changes() -> None:
    """Load a seccomp filter into this process and its children under which every call of
    ``ATTRIBUTE_CALLS``, ``IDENTITY_CALLS``, ``RING_AND_WATCH_CALLS`` and ``NAMESPACE_CALLS`` (and
    ``NEWER_CALLS``), of ``ARGUMENT_RULES`` with those arguments, and of ``clone`` with a flag of
    ``NAMESPACE_FLAGS``, fails with EPERM, and ``clone3`` with ENOSYS; other calls are unchanged.
    Needs no_new_privs set first. Raises OSError, or RuntimeError when libseccomp is missing."""
    import pyseccomp  # here, not at the top: the launcher still starts, and says so, without libseccomp

    rules = pyseccomp.SyscallFilter(pyseccomp.ALLOW)
    for name in (*ATTRIBUTE_CALLS, *IDENTITY_CALLS, *RING_AND_WATCH_CALLS, *NAMESPACE_CALLS):
        number = pyseccomp.resolve_syscall(pyseccomp.Arch.NATIVE, name)
        if number >= 0:  # a call this architecture has
            rules.add_rule(pyseccomp.ERRNO(errno.EPERM), number)
    for number in NEWER_CALLS.get(pyseccomp.system_arch(), ()):
        rules.add_rule(pyseccomp.ERRNO(errno.EPERM), number)
    for flag in NAMESPACE_FLAGS:  # clone's flags are its first argument on x86-64 and arm64
        rules.add_rule(pyseccomp.ERRNO(errno.EPERM), "clone", pyseccomp.Arg(0, pyseccomp.MASKED_EQ, flag, flag))
    rules.add_rule(pyseccomp.ERRNO(errno.ENOSYS), "clone3")
    for name, refused in ARGUMENT_RULES.items():
        for index, value in refused:
            rules.add_rule(pyseccomp.ERRNO(errno.EPERM), name, pyseccomp.Arg(index, pyseccomp.EQ, value))
    # preadv2 with a flag (RWF_NOWAIT reads whether a page is cached)
    rules.add_rule(pyseccomp.ERRNO(errno.EPERM), "preadv2", pyseccomp.Arg(5, pyseccomp.NE, 0))
    rules.load()


def keep_access_times() -> None:
    """Run by root: move this process into a mount namespace of its own where every mount is
    ``noatime``, so that nothing this process and its children read, or follow (a symbolic link's
    own access time), changes an access time. Landlock does not control ``stat()``: kernels that read
    files every kernel may read, or followed links, at chosen moments passed a classmate's functions
    to a later kernel through their access times. (Made by root, before the user namespace, the
    namespace's mounts are not locked; a plain user's would be, and could not be changed.) Raises
    OSError when a mount of a file system that holds files is refused."""
    _check(_libc().unshare(CLONE_NEWNS), "unshare(CLONE_NEWNS)")
    _mount(None, "/", MS_REC | MS_PRIVATE)  # nothing done here reaches the machine's own mounts
    for line in Path("/proc/self/mountinfo").read_text().splitlines():
        fields = line.split()
        point = re.sub(r"\\([0-7]{3})", lambda m: chr(int(m.group(1), 8)), fields[4])  # "\040" is a space
        kind = fields[fields.index("-") + 1]
        try:
            kept = os.statvfs(point).f_flag & (os.ST_RDONLY | os.ST_NOSUID | os.ST_NODEV | os.ST_NOEXEC)  # as MS_*
            _mount(None, point, MS_REMOUNT | MS_BIND | MS_NOATIME | kept)
        except OSError:
            if kind not in PSEUDO_FILE_SYSTEMS:
                raise


PSEUDO_FILE_SYSTEMS = frozenset({"proc", "sysfs", "cgroup", "cgroup2", "devpts", "mqueue", "debugfs", "tracefs",
                                 "securityfs", "pstore", "bpf", "fusectl", "configfs", "hugetlbfs", "binfmt_misc",
                                 "autofs", "efivarfs", "nsfs", "rpc_pipefs"})
"""File systems whose mounts may refuse the remount: they hold no file a kernel reads for its access time."""


def _mount(source: str | None, target: str, flags: int) -> None:
    """mount(2) with no file system type or data; raises OSError if it fails."""
    _check(_libc().mount(source.encode() if source else None, target.encode(), None, flags, None), f"mount({target})")


def confine(read: list[str], write: list[str], layers: tuple[str, ...] = LAYERS, own: tuple[str, ...] = (),
            uid: int | None = None) -> list[str]:
    """Apply the sandbox's ``layers`` to this process: the network and PID namespaces (returning in
    a grandchild, see ``run_below_namespace_init``, capped at MAX_TASKS tasks),
    no core dumps, no_new_privs, then Landlock. Run by root with the network layer, first give the
    folders ``own`` to the kernel's own user (``kernel_uid(uid)``): with mode 0700 they are then closed to
    every other kernel, whose capabilities reach only root's files and its own (Landlock does not
    control connecting to a Unix socket by its path; this keeps a kernel from the sockets in another
    kernel's private folder). Returns what could not be applied, one sentence each (empty when all
    was)."""
    if sys.platform != "linux":
        return [f"not applied: {', '.join(layers)} confinement needs Linux"] if layers else []
    problems = []
    if "network" in layers and os.getuid() == 0:
        for folder in own:
            os.chown(folder, kernel_uid(uid), kernel_uid(uid), follow_symlinks=False)
            os.chmod(folder, 0o700, follow_symlinks=False)
        try:
            keep_access_times()
        except OSError as error:
            problems.append(f"access times not kept, kernels can signal each other through them ({error})")
    if "network" in layers:
        try:
            enter_network_namespace(uid)
        except OSError as error:
            problems.append(f"no network namespace, the kernel has the network ({_namespace_error(error.errno)})")
        else:
            run_below_namespace_init()
            # counted in the kernel's own user namespace; not for root's user ID, which Linux exempts
            resource.setrlimit(resource.RLIMIT_NPROC, (MAX_TASKS, MAX_TASKS))
            try:
                drop_capabilities()
            except OSError as error:
                problems.append(f"capabilities kept, the kernel is root in its namespace ({error})")
    # no core dumps: a crash would write the kernel's memory (up to its 4 GiB) to disk, in its folder,
    # or outside the sandbox where a helper collects cores (systemd-coredump, apport)
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
    try:
        set_no_new_privs()
    except OSError as error:
        problems.append(f"no_new_privs not set ({error})")
    if "files" in layers:
        try:  # before Landlock: loading libseccomp looks for it with ldconfig, in a temporary folder
            forbid_attribute_changes()
        except (OSError, RuntimeError) as error:
            problems.append("no seccomp filter, the kernel can change the mode, owner and times of files it can "
                            f"name ({error})")
        try:
            skipped = restrict_files(read, write)
        except OSError as error:
            problems.append(f"Landlock not applied, the kernel can read every file this user can ({error})")
        else:
            problems += [f"not allowed, it stays closed: {path}" for path in skipped]
    return problems


def main(argv: list[str] | None = None) -> None:
    """The launcher: confine this process as the arguments say, report on stderr what could not be
    applied, and exec the command. Does not return."""
    parser = argparse.ArgumentParser(
        prog="python -m autograder.kernel.sandbox",
        description="Run a command confined: it reads only beneath --read paths, writes only beneath "
                    "--write paths, and has no network. Layers the OS lacks are left out, and said.")
    parser.add_argument("--read", action="append", default=[], metavar="PATH", help="a path it may read beneath")
    parser.add_argument("--write", action="append", default=[], metavar="PATH",
                        help="a path it may read and write beneath")
    parser.add_argument("--without", action="append", default=[], choices=LAYERS,
                        help="a layer to leave out")
    parser.add_argument("--own", action="append", default=[], metavar="FOLDER",
                        help="run by root: a folder to give to the kernel's own user (mode 0700)")
    parser.add_argument("--uid", type=int, metavar="UID",
                        help=f"run by root: the kernel's own user ID, from {KERNEL_UIDS_FROM} to 2**31 - 1 "
                             "(default: the first plus the launcher's process ID)")
    parser.add_argument("command", nargs=argparse.REMAINDER, help="-- CMD ARGS...")
    args = parser.parse_args(argv)
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        parser.error("no command to run: give it after --")
    if args.uid is not None and not KERNEL_UIDS_FROM <= args.uid < 2**31:
        parser.error(f"--uid {args.uid}: it is from {KERNEL_UIDS_FROM} to 2**31 - 1")
    program = shutil.which(command[0])
    if program is None:
        parser.error(f"{command[0]}: no such program")
    layers = tuple(layer for layer in LAYERS if layer not in args.without)
    for problem in confine(args.read, args.write, layers, tuple(args.own), args.uid):
        print(f"sandbox: {problem}", file=sys.stderr)
    sys.stderr.flush()
    os.execv(program, command)


def launcher_command(read: list[str], write: list[str], layers: tuple[str, ...], own: list[str] = (),
                     uid: int | None = None) -> list[str]:
    """The launcher's command line for these paths, layers, folders of the kernel's own and user ID
    (see ``confine``), up to ``--``: the command it confines follows. It runs isolated (``-I``), so that
    nothing in the working directory or the environment can stand in for the modules it imports."""
    command = [sys.executable, "-I", str(Path(__file__).resolve())]
    command += [arg for path in read for arg in ("--read", path)]
    command += [arg for path in write for arg in ("--write", path)]
    command += [arg for path in own for arg in ("--own", path)]
    command += ["--uid", str(uid)] if uid is not None else []
    command += [arg for layer in LAYERS if layer not in layers for arg in ("--without", layer)]
    return [*command, "--"]


if __name__ == "__main__":
    main()

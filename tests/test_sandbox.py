"""The grading kernel's sandbox (autograder/kernel/sandbox.py, autograder/kernel/manager.py), with real
processes: the launcher on small commands, and real kernels started by SandboxedKernelManager.

Each probe runs in the confined process and reports what happened ("ok", or the exception); the
same probes run unconfined (KIT_SANDBOX=off, or a plain subprocess) succeed, so that every refusal
seen here is the sandbox's doing. The course root's hidden files are the real ones; the graded
class (gradebook, other students' folders) is a temporary course folder, as grading uses one.
"""

from __future__ import annotations

import asyncio
import ctypes
import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path

import landlockpy
import pyseccomp
import nbformat
import pytest
from nbclient import NotebookClient
from nbformat.v4 import new_code_cell, new_notebook

from autograder.authoring import build
from autograder.kernel import manager, sandbox
from autograder.labs import ROOT
from autograder.kernel.manager import PRIVATE_PARENT, SandboxedKernelManager
from autograder.kernel.sandbox import launcher_command
from autograder.kernel.remove_tree import remove_tree

KERNEL_ARGUMENTS = ["--HistoryManager.hist_file=:memory:", "--IPKernelApp.log_level=ERROR"]

PROBE_HELPERS = """
import errno, json, os, socket

def attempt(action):
    try:
        action()
        return "ok"
    except OSError as error:
        return errno.errorcode.get(error.errno, type(error).__name__) if error.errno else type(error).__name__
    except Exception as error:
        return type(error).__name__

def check(condition):
    if not condition:
        raise AssertionError

def read(path):
    with open(path, "rb") as f:
        f.read(1)

def write(path):
    with open(path, "w") as f:
        f.write("written by the kernel")

def connect(port):
    with socket.create_connection(("127.0.0.1", port), timeout=5):
        pass
"""


@pytest.fixture
def graded_class(tmp_path: Path) -> dict[str, Path]:
    """A course folder being graded: a gradebook, Alice's folder (the kernel's) and Bob's work."""
    work = tmp_path / "course"
    alice = work / "autograded" / "alice" / "train-kf"
    bob = work / "autograded" / "bob" / "train-kf" / "train-kf.ipynb"
    bob_submitted = work / "submitted" / "bob" / "train-kf" / "train-kf.ipynb"
    for path in (bob, bob_submitted):
        path.parent.mkdir(parents=True)
        path.write_text("Bob's answers")
    alice.mkdir(parents=True)
    (work / "gradebook.db").write_text("every grade")
    return {"work": work, "alice": alice, "bob": bob, "bob_submitted": bob_submitted}


@pytest.fixture
def planted() -> Iterator[Path]:
    """A file in the course root that a kernel tries to write; removed afterwards if it could."""
    path = ROOT / "planted.py"
    yield path
    path.unlink(missing_ok=True)


@pytest.fixture
def tcp_server() -> Iterator[int]:
    """A TCP server listening on 127.0.0.1 in this process; yields its port."""
    with socket.create_server(("127.0.0.1", 0)) as server:
        yield server.getsockname()[1]


def run_in_kernel(code: str, cwd: Path, prepare: Callable[[Path], object] = lambda private: None) -> str:
    """Start a kernel with SandboxedKernelManager in ``cwd``, call ``prepare`` with its private
    folder, run ``code``, shut the kernel down; returns what it printed. Checks that the private
    folder existed and is gone afterwards."""

    async def run() -> str:
        """What the kernel printed."""
        manager = SandboxedKernelManager(kernel_name="python3")
        await manager.start_kernel(cwd=str(cwd), extra_arguments=KERNEL_ARGUMENTS)
        private = manager.private_folder
        assert private is not None and private.is_dir() and private.parent == Path(PRIVATE_PARENT)
        prepare(private)
        client = manager.client()
        client.start_channels()
        printed: list[str] = []
        try:
            await client.wait_for_ready(timeout=120)
            reply = await client.execute_interactive(code, timeout=120, output_hook=lambda msg: printed.append(
                msg["content"]["text"] if msg["msg_type"] == "stream" else ""))
            assert reply["content"]["status"] == "ok", reply["content"]
        finally:
            client.stop_channels()
            await manager.shutdown_kernel()
        assert not private.exists(), "the private folder outlived the kernel"
        return "".join(printed)

    return asyncio.run(run())


def probe_results(probes: dict[str, str], run) -> dict[str, str]:
    """Each probe (name -> Python expression to attempt) run by ``run`` (code -> its output)."""
    body = "\n".join(f"results[{name!r}] = attempt(lambda: {expression})" for name, expression in probes.items())
    return json.loads(run(f"{PROBE_HELPERS}\nresults = {{}}\n{body}\nprint(json.dumps(results))").splitlines()[-1])


def hidden_file_probes(graded_class: dict[str, Path]) -> dict[str, str]:
    """What a cheat would try: the reference, the pipeline, the sources, the gradebook, another
    student's work, and writing outside its own folder."""
    work = graded_class["work"]
    return {
        # the grading kernel's environment has no PYTHONPATH: a cheat puts the course root on sys.path first
        "import solutions": f"(__import__('sys').path.insert(0, {str(ROOT)!r}), __import__('solutions.train_kf.reference'))",
        "read solutions/train_kf/reference.py": f"read({str(ROOT / 'solutions' / 'train_kf' / 'reference.py')!r})",
        "read autograder/__init__.py": f"read({str(ROOT / 'autograder' / '__init__.py')!r})",
        "read the source notebook": f"read({str(ROOT / 'source' / 'train-kf' / 'train-kf.ipynb')!r})",
        "read nbgrader_config.py": f"read({str(ROOT / 'nbgrader_config.py')!r})",
        "read gradebook.db": f"read({str(work / 'gradebook.db')!r})",
        "read Bob's graded notebook": f"read({str(graded_class['bob'])!r})",
        "read Bob's submission": f"read({str(graded_class['bob_submitted'])!r})",
        "list the graded class": f"os.listdir({str(work / 'autograded')!r})",
        "write in the course folder": f"write({str(work / 'grades.csv')!r})",
        "write in the course root": f"write({str(ROOT / 'planted.py')!r})",
    }


def test_status_reports_what_this_machine_offers():
    raw = ctypes.CDLL(None, use_errno=True).syscall(444, None, 0, 1)  # landlock_create_ruleset(NULL, 0, VERSION)
    can_unshare = subprocess.run(["unshare", "--map-root-user", "--net", "true"]).returncode == 0
    assert raw > 0, "this machine has no Landlock: the sandbox cannot confine files here"
    assert can_unshare, "this machine makes no network namespaces: the sandbox cannot cut the network here"
    found = sandbox.status()
    assert (found.landlock_abi, found.network_namespace, found.complete) == (raw, True, True)
    assert found.summary == (f"Landlock ABI {raw} and a seccomp filter (files) and private network and PID namespaces (no network, no "
                             f"process outlives the kernel, and at most {sandbox.MAX_TASKS} processes in it)")


@pytest.mark.parametrize("value, layers, starts, ends", [
    ("on", ("files", "network"), "Landlock ABI", "(no network, no process outlives the kernel, and at most 256 processes in it)"),
    ("off", (), "NOT SANDBOXED: Landlock turned off (KIT_SANDBOX=off), and network namespace turned off",
     "the grading kernel can read every file the grader's user can, and use the network"),
    ("files", ("files",), "PARTLY SANDBOXED: Landlock ABI", "the grading kernel can use the network"),
    ("network", ("network",), "PARTLY SANDBOXED: Landlock turned off (KIT_SANDBOX=network) and private network",
     "the grading kernel can read every file the grader's user can"),
])
def test_kit_sandbox_turns_layers_off_and_status_says_so(monkeypatch, value, layers, starts, ends):
    monkeypatch.setenv("KIT_SANDBOX", value)
    found = sandbox.status()
    assert sandbox.wanted_layers() == layers
    assert (found.files, found.network, found.complete) == ("files" in layers, "network" in layers, len(layers) == 2)
    assert found.summary.startswith(starts) and found.summary.endswith(ends), found.summary


def test_kit_sandbox_refuses_an_unknown_word(monkeypatch):
    monkeypatch.setenv("KIT_SANDBOX", "files,disk")
    with pytest.raises(ValueError, match="KIT_SANDBOX"):
        sandbox.wanted_layers()


def launch(tmp_path: Path, code: str, *options: str) -> subprocess.CompletedProcess:
    """``code`` run by this Python through the launcher: it may read this Python's installation and
    read and write ``tmp_path/allowed``; ``options`` are more launcher options."""
    read = [sys.prefix, sys.base_prefix, os.path.realpath(sys.executable), "/usr/lib", "/lib", "/lib64",
            "/etc/ld.so.cache"]
    command = launcher_command([p for p in read if os.path.exists(p)], [str(tmp_path / "allowed")], sandbox.LAYERS)
    command[-1:-1] = options
    return subprocess.run([*command, sys.executable, "-I", "-c", code], capture_output=True, text=True, timeout=60)


def launched_probes(tmp_path: Path, probes: dict[str, str], *options: str) -> dict[str, str]:
    """Each probe's result in a process started by the launcher."""
    def run(code: str) -> str:
        """What the confined process printed."""
        done = launch(tmp_path, code, *options)
        assert done.returncode == 0, done.stderr
        return done.stdout
    return probe_results(probes, run)


def test_the_launcher_confines_files_and_network(tmp_path, tcp_server):
    allowed, readable, closed = tmp_path / "allowed", tmp_path / "readable", tmp_path / "closed"
    for folder in (allowed, readable, closed):
        folder.mkdir()
    (closed / "secret.txt").write_text("secret")
    (readable / "data.txt").write_text("data")
    (allowed / "old.txt").write_text("old")
    probes = {
        "read beneath --read": f"read({str(readable / 'data.txt')!r})",
        "write beneath --read": f"write({str(readable / 'planted.txt')!r})",
        "write beneath --write": f"write({str(allowed / 'new.txt')!r})",
        "make a folder beneath --write": f"os.makedirs({str(allowed / 'a' / 'b')!r})",
        "remove beneath --write": f"os.remove({str(allowed / 'old.txt')!r})",
        "bind a Unix socket beneath --write": f"socket.socket(socket.AF_UNIX).bind({str(allowed / 's')!r})",
        "read elsewhere": f"read({str(closed / 'secret.txt')!r})",
        "list elsewhere": f"os.listdir({str(closed)!r})",
        "write elsewhere": f"write({str(closed / 'planted.txt')!r})",
        "connect to 127.0.0.1": f"connect({tcp_server})",
    }
    assert launched_probes(tmp_path, probes, "--read", str(readable)) == {
        "read beneath --read": "ok",
        "write beneath --read": "EACCES",
        "write beneath --write": "ok",
        "make a folder beneath --write": "ok",
        "remove beneath --write": "ok",
        "bind a Unix socket beneath --write": "ok",
        "read elsewhere": "EACCES",
        "list elsewhere": "EACCES",
        "write elsewhere": "EACCES",
        "connect to 127.0.0.1": "ENETUNREACH",
    }
    assert not (closed / "planted.txt").exists() and not (readable / "planted.txt").exists()
    assert not (allowed / "old.txt").exists() and (allowed / "a" / "b").is_dir()
    # the same probes, unconfined: every refusal above was the sandbox's
    unconfined = subprocess.run([sys.executable, "-c", f"{PROBE_HELPERS}\nread({str(closed / 'secret.txt')!r})\n"
                                 f"connect({tcp_server})\nprint('ok')"], capture_output=True, text=True)
    assert unconfined.stdout.strip() == "ok", unconfined.stderr


def test_the_launcher_leaves_out_a_layer_and_says_what_it_could_not_allow(tmp_path, tcp_server):
    (tmp_path / "allowed").mkdir()
    secret = tmp_path / "secret.txt"
    secret.write_text("secret")
    probes = {"read elsewhere": f"read({str(secret)!r})", "connect to 127.0.0.1": f"connect({tcp_server})"}
    assert launched_probes(tmp_path, probes, "--without", "network") == {
        "read elsewhere": "EACCES", "connect to 127.0.0.1": "ok"}
    assert launched_probes(tmp_path, probes, "--without", "files") == {
        "read elsewhere": "ok", "connect to 127.0.0.1": "ENETUNREACH"}
    done = launch(tmp_path, "print('ran')", "--read", str(tmp_path / "missing"))
    assert done.stdout == "ran\n"
    assert f"sandbox: not allowed, it stays closed: {tmp_path / 'missing'} (No such file or directory)" in done.stderr


def test_a_sandboxed_kernel_runs_the_labs_work_and_reaches_nothing_else(graded_class, tcp_server, planted):
    alice = graded_class["alice"]
    probes = {
        "NumPy, SciPy": "__import__('scipy.linalg').linalg.solve(__import__('numpy').eye(2), [1, 2])",
        "a Matplotlib figure in its folder": (
            "(__import__('matplotlib').use('Agg'), __import__('matplotlib.pyplot').pyplot.subplots()[0]"
            ".savefig('figure.png'))"),
        "the course package and its data": "__import__('course.train').train.load()",
        "write in its folder": "write('notes.txt')",
        "write in TMPDIR": "__import__('tempfile').NamedTemporaryFile().close()",
        "TMPDIR in the private folder": f"check(__import__('tempfile').gettempdir().startswith('{PRIVATE_PARENT}/kit-'))",
        "course from the course root": f"check(os.path.realpath(__import__('course').__file__) == {str(ROOT / 'course' / '__init__.py')!r})",
        "read /proc/self": "read('/proc/self/status')",
        "read another process": "read('/proc/1/cmdline')",
        "list /tmp": "os.listdir('/tmp')",
        "write in /tmp": "write('/tmp/planted.txt')",
        "connect to 127.0.0.1": f"connect({tcp_server})",
        **hidden_file_probes(graded_class),
    }
    found = probe_results(probes, lambda code: run_in_kernel(code, alice))
    assert found == {
        "NumPy, SciPy": "ok",
        "a Matplotlib figure in its folder": "ok",
        "the course package and its data": "ok",
        "write in its folder": "ok",
        "write in TMPDIR": "ok",
        "TMPDIR in the private folder": "ok",
        "course from the course root": "ok",
        "read /proc/self": "ok",
        "read another process": "EACCES",
        "list /tmp": "EACCES",
        "write in /tmp": "EACCES",
        "connect to 127.0.0.1": "ENETUNREACH",
        "import solutions": "ModuleNotFoundError",
        "read solutions/train_kf/reference.py": "EACCES",
        "read autograder/__init__.py": "EACCES",
        "read the source notebook": "EACCES",
        "read nbgrader_config.py": "EACCES",
        "read gradebook.db": "EACCES",
        "read Bob's graded notebook": "EACCES",
        "read Bob's submission": "EACCES",
        "list the graded class": "EACCES",
        "write in the course folder": "EACCES",
        "write in the course root": "EACCES",
    }
    assert (alice / "figure.png").stat().st_size > 0 and (alice / "notes.txt").exists()
    assert not planted.exists() and not (graded_class["work"] / "grades.csv").exists()


def test_a_kernel_holds_none_of_the_graders_terminal_or_log(graded_class, capfd):
    """Adversarial review: the kernel inherited the grader's stdin, stdout and stderr, so it could read the
    instructor's typeahead from the terminal, truncate and flood the grading log, and write escape codes
    or forged table rows into the grader's output. Its descriptors 0, 1 and 2 are now /dev/null."""
    code = PROBE_HELPERS + """
import stat, sys
null = os.stat("/dev/null").st_rdev
# ipykernel keeps a copy of the descriptors it was started with, before it captured 1 and 2 for the notebook
started = [0, sys.stdout._original_stdstream_copy, sys.stderr._original_stdstream_copy]
for fd in started[1:]:
    os.write(fd, b"KIT-FORGED-ROW alice 9/9 full marks\\n")
print(json.dumps([stat.S_ISCHR(os.fstat(fd).st_mode) and os.fstat(fd).st_rdev == null for fd in started]))
"""
    printed = run_in_kernel(code, graded_class["alice"])
    assert json.loads(printed.strip().splitlines()[-1]) == [True, True, True], printed
    grader = capfd.readouterr()
    assert "KIT-FORGED-ROW" not in grader.out + grader.err


NEST = """
import os
for _ in range(3000):  # past PATH_MAX, by chdir, deeper than shutil.rmtree's recursion in Python 3.11
    os.mkdir("d")
    os.chdir("d")
open("payload", "w").write("left behind")
"""


def test_a_folder_a_kernel_nested_3000_deep_is_removed(tmp_path):
    """Adversarial review: shutil.rmtree raised RecursionError on it (ignore_errors does not cover that),
    so the kernel's private folder and the scratch copy stayed in /tmp and the submission was not graded."""
    subprocess.run([sys.executable, "-c", NEST], cwd=tmp_path, check=True)
    with pytest.raises(RecursionError):
        shutil.rmtree(tmp_path / "d", ignore_errors=True)
    remove_tree(tmp_path / "d")
    assert not (tmp_path / "d").exists()


def test_a_kernel_that_nests_its_private_folder_deep_leaves_nothing(graded_class):
    """run_in_kernel asserts that the private folder is gone after the kernel."""
    run_in_kernel(f"os = __import__('os'); os.chdir(os.environ['TMPDIR']); exec({NEST!r})", graded_class["alice"])


def test_a_grading_kernel_gets_none_of_the_graders_secrets_in_its_environment(graded_class, monkeypatch):
    """The grader's environment may name the gradebook with its password (GRADEBOOK_URL), hold
    PGPASSWORD or name the grading secret's file; a kernel could print them into its feedback page.
    It gets only the variables a Python program needs (manager.KERNEL_ENVIRONMENT), and
    NBGRADER_EXECUTION, which course.checks reads."""
    secrets = {"GRADEBOOK_URL": "postgresql+psycopg://grader:hunter2@db:5432/course", "PGPASSWORD": "hunter2",
               "KIT_GRADING_SECRET_FILE": "/srv/secret", "AWS_SECRET_ACCESS_KEY": "hunter2"}
    for name, value in {**secrets, "NBGRADER_EXECUTION": "autograde", "OPENBLAS_NUM_THREADS": "1"}.items():
        monkeypatch.setenv(name, value)
    printed = run_in_kernel("import os, json\nprint(json.dumps(dict(os.environ)))", graded_class["alice"])
    seen = json.loads(printed)
    assert not set(secrets) & set(seen) and "hunter2" not in printed, seen
    assert seen["NBGRADER_EXECUTION"] == "autograde" and seen["OPENBLAS_NUM_THREADS"] == "1", seen


def test_with_kit_sandbox_off_the_kernel_still_runs_and_reaches_everything(monkeypatch, graded_class, tcp_server):
    monkeypatch.setenv("KIT_SANDBOX", "off")
    assert sandbox.status().summary.startswith("NOT SANDBOXED")
    probes = {"connect to 127.0.0.1": f"connect({tcp_server})", **hidden_file_probes(graded_class)}
    del probes["write in the course root"]  # the real course root: not written while other tests read it
    found = probe_results(probes, lambda code: run_in_kernel(code, graded_class["alice"]))
    assert found == {name: "ok" for name in probes}
    assert (graded_class["work"] / "grades.csv").exists()


def test_nbclient_runs_a_notebook_in_the_sandbox(graded_class):
    alice = graded_class["alice"]
    nb = new_notebook(cells=[
        new_code_cell("open('answer.txt', 'w').write('42')"),
        new_code_cell(f"open({str(ROOT / 'solutions' / 'train_kf' / 'reference.py')!r}).read()"),
        new_code_cell("print(open('answer.txt').read())"),
    ])
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    NotebookClient(nb, kernel_manager_class=SandboxedKernelManager, allow_errors=True, timeout=120,
                   startup_timeout=120, extra_arguments=KERNEL_ARGUMENTS,
                   resources={"metadata": {"path": str(alice)}}).execute()
    nbformat.validate(nb)
    assert (alice / "answer.txt").read_text() == "42"
    assert [o.get("ename") for o in nb.cells[1].outputs] == ["PermissionError"]
    assert nb.cells[2].outputs[0]["text"] == "42\n"


def test_a_restarted_kernel_keeps_its_files(tmp_path):
    """The grader restarts a kernel that timed out or died, in the same folders. Run by root, a kernel
    is a user of its own, and only its own files are its to replace: the restarted kernel is the
    same user, so it replaces what the first one wrote, in its working folder and its private one.
    (With a user ID per launch, the restarted kernel's write failed with PermissionError.)"""
    code = ("import os\nfor folder in ('.', os.environ['TMPDIR']):\n    with open(os.path.join(folder, 'kept.txt'), 'w') as f:"
            "\n        f.write(str(os.getpid()))\nprint('wrote')")

    async def run() -> list[str]:
        """What each of the two kernels printed."""
        manager = SandboxedKernelManager(kernel_name="python3")
        await manager.start_kernel(cwd=str(tmp_path), extra_arguments=KERNEL_ARGUMENTS)
        printed: list[str] = []
        try:
            for start in range(2):
                if start:
                    await manager.restart_kernel(now=True)
                client = manager.client()
                client.start_channels()
                try:
                    await client.wait_for_ready(timeout=120)
                    reply = await client.execute_interactive(code, timeout=120, output_hook=lambda msg: printed.append(
                        msg["content"]["text"] if msg["msg_type"] == "stream" else ""))
                    assert reply["content"]["status"] == "ok", reply["content"]["evalue"]
                finally:
                    client.stop_channels()
        finally:
            await manager.shutdown_kernel()
        return printed

    assert "".join(asyncio.run(run())) == "wrote\nwrote\n"


def test_a_restart_writes_nothing_where_the_kernel_before_put_a_link(tmp_path):
    """On a restart the manager copied Matplotlib's font list into the private folder's matplotlib/
    again; the kernel before had replaced that folder with a link to a file of the grader's, and the
    grader, as root, overwrote the file with the font list (a re-attack of issue 29). The font list
    is now copied only into the folder just made. On the code before, the file held the font list."""
    victim = tmp_path / "gradebook.db"
    victim.write_text("grades")
    code = (f"import os, shutil\nfolder = os.environ['MPLCONFIGDIR']\nshutil.rmtree(folder)\n"
            f"os.symlink({str(victim)!r}, folder)\nprint('linked')")

    async def run() -> str:
        """What the first kernel printed; the second only starts."""
        manager = SandboxedKernelManager(kernel_name="python3")
        await manager.start_kernel(cwd=str(tmp_path / "work"), extra_arguments=KERNEL_ARGUMENTS)
        printed: list[str] = []
        try:
            client = manager.client()
            client.start_channels()
            try:
                await client.wait_for_ready(timeout=120)
                await client.execute_interactive(code, timeout=120, output_hook=lambda msg: printed.append(
                    msg["content"]["text"] if msg["msg_type"] == "stream" else ""))
            finally:
                client.stop_channels()
            await manager.restart_kernel(now=True)
        finally:
            await manager.shutdown_kernel()
        return "".join(printed)

    (tmp_path / "work").mkdir()
    assert asyncio.run(run()) == "linked\n"
    assert victim.read_text() == "grades"


def test_the_grader_and_the_kernel_meet_on_a_unix_socket_in_the_private_folder(graded_class):
    """How the grader will serve the comparison: a socket it makes in the private folder."""
    servers: list[socket.socket] = []

    def listen(private: Path) -> None:
        """A Unix socket server in the private folder, as the grader will make one."""
        servers.append(socket.socket(socket.AF_UNIX))
        servers[0].bind(str(private / "grader.sock"))
        servers[0].listen()

    code = ("import os, socket\nwith socket.socket(socket.AF_UNIX) as s:\n"
            "    s.connect(os.path.join(os.path.dirname(os.environ['TMPDIR']), 'grader.sock'))\n"
            "    s.sendall(b'outputs of the student function')\n    print('sent')")
    try:
        assert run_in_kernel(code, graded_class["alice"], listen) == "sent\n"
        connection, _ = servers[0].accept()
        with connection:
            assert connection.recv(100) == b"outputs of the student function"
    finally:
        servers[0].close()


@pytest.mark.parametrize("option", ["cwd", "read_paths", "write_paths"])
def test_a_kernel_allowed_the_course_root_is_not_started(option):
    km = SandboxedKernelManager(kernel_name="python3", **({} if option == "cwd" else {option: [str(ROOT.parent)]}))
    with pytest.raises(ValueError, match="holds the course root"):
        asyncio.run(km.start_kernel(cwd=str(ROOT) if option == "cwd" else None))
    assert km.private_folder is None and not km.has_kernel


def test_the_private_folder_is_short_enough_for_unix_sockets():
    km = SandboxedKernelManager(kernel_name="python3")
    private = km._make_private_folder()
    try:
        assert len(f"{private}/comparison.sock".encode()) < 107 - 20
        assert Path(km.connection_file).parent == private and km.ip == str(private / "ipc")
    finally:
        shutil.rmtree(private)


@pytest.mark.skipif(os.getuid() != 0, reason="already not root: every other test here runs as a plain user")
def test_the_launcher_confines_a_plain_user_too(tcp_server):
    """As root: the launcher run by user nobody, with Debian's Python (this one is in root's home),
    from a copy that nobody can read (the course root may be in a folder closed to others)."""
    python, setpriv = shutil.which("python3", path="/usr/bin"), shutil.which("setpriv")
    if python is None or setpriv is None:
        pytest.skip("needs Debian's /usr/bin/python3 and setpriv (util-linux)")
    with tempfile.TemporaryDirectory(prefix="kit-test-") as tmp:
        folder = Path(tmp)
        folder.chmod(0o755)
        shutil.copytree(Path(landlockpy.__file__).parent, folder / "landlockpy")
        shutil.copy(pyseccomp.__file__, folder)  # the launcher's other import
        shutil.copy(sandbox.__file__, folder)
        allowed, secret = folder / "allowed", folder / "secret.txt"
        allowed.mkdir()
        shutil.chown(allowed, "nobody")
        secret.write_text("secret")
        probe = (f"{PROBE_HELPERS}\nprint(json.dumps({{'uid': os.getuid(), 'write': attempt(lambda: write("
                 f"{str(allowed / 'x.txt')!r})), 'read': attempt(lambda: read({str(secret)!r})), "
                 f"'connect': attempt(lambda: connect({tcp_server}))}}))")
        as_nobody = [setpriv, "--reuid=nobody", "--regid=nogroup", "--clear-groups"]
        launcher = [python, str(folder / "sandbox.py"), "--read", "/usr", "--read", "/etc/ld.so.cache",
                    "--write", str(allowed), "--"]
        done = subprocess.run([*as_nobody, *launcher, python, "-I", "-c", probe],
                              capture_output=True, text=True, timeout=60, cwd="/")
        assert done.returncode == 0 and done.stderr == "", done.stderr
        assert json.loads(done.stdout) == {"uid": 65534, "write": "ok", "read": "EACCES", "connect": "ENETUNREACH"}
        assert secret.stat().st_mode & 0o004, "the secret is readable by others: only the sandbox keeps nobody out"


def test_a_kernel_imports_the_course_package_of_the_root_being_graded(graded_class, tmp_path, monkeypatch):
    """Issue 32: kernels imported the *installed* ``course``, which ``-e .`` from another checkout (a
    second course folder, a shared environment) makes another checkout's, so a class was graded with
    code other than the root's, silently. Here the root being graded is a second checkout whose
    ``course/`` carries a marker; this environment's ``-e .`` points elsewhere. On the code before,
    the kernel imported the installed package, without the marker."""
    other = tmp_path / "other-checkout"
    shutil.copytree(manager.ROOT / "course", other / "course", ignore=shutil.ignore_patterns("__pycache__"))
    with (other / "course" / "__init__.py").open("a") as init:
        init.write("\nCHECKOUT_MARKER = 'the other checkout'\n")
    monkeypatch.setattr(manager, "ROOT", other)
    manager.course_site.cache_clear()
    try:
        printed = run_in_kernel("import os, course\nprint(os.path.realpath(course.__file__), "
                                "getattr(course, 'CHECKOUT_MARKER', 'none'), sep='|')", graded_class["alice"])
    finally:
        manager.course_site.cache_clear()
    path, marker = printed.strip().split("|")
    assert marker == "the other checkout" and path == str((other / "course" / "__init__.py").resolve()), printed


def test_build_and_grading_kernels_import_the_same_course_package(graded_class, tmp_path):
    """Issue 32: ``build`` (autograder/authoring/build.py) and grading start their kernels in different ways (a
    build's kernel runs the hidden blocks, and so imports ``solutions``, which no grading kernel may), but both
    import this root's ``course``, whatever checkout the environment's ``-e .`` points at."""
    code = "import os, course\nprint(os.path.realpath(course.__file__))"
    nb = new_notebook(cells=[new_code_cell(code)], metadata={"kernelspec": build.KERNELSPEC})
    (tmp_path / "built").mkdir()
    assert build.execute(nb, tmp_path / "built") == []
    built = nb.cells[0].outputs[0]["text"].strip()
    assert built == run_in_kernel(code, graded_class["alice"]).strip() == str((ROOT / "course" / "__init__.py").resolve())

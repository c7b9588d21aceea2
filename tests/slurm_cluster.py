"""A throwaway single-node Slurm cluster for the tests, on 127.0.0.1.

``running_cluster()`` starts, from Debian's ``munge`` and ``slurm-wlm`` (22.05) packages, a ``munged``
with a key of its own, then ``slurmctld`` and ``slurmd`` with a ``slurm.conf`` of their own, all in a
new temporary folder and on free ports of 127.0.0.1 (the controller is named after this machine, as
slurmctld insists, but listens on its loopback address), and yields a Cluster whose commands
(``sbatch``, ``scancel``, ``scontrol``) use that configuration through $SLURM_CONF. On exit it cancels
every job, stops the three daemons and removes the folder. Nothing of the system's Slurm or munge
(``/etc/slurm``, ``/etc/munge``, their services) is read or changed.

The node has this machine's cores and memory. Jobs run as the user who submits them, which slurmd can
do only as root: the tests that use it need root (tests/machine_needs.py), as CI runs.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import signal
import socket
import subprocess
import tempfile
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

START_TIMEOUT = 60.0
"""Seconds for munged to answer and for the node to be idle in its partition."""
PROGRAMS = ("munged", "slurmctld", "slurmd", "sbatch", "scancel", "scontrol", "sinfo", "squeue")
NODE = "localhost"
FINISHED = ("COMPLETED", "FAILED", "CANCELLED", "TIMEOUT", "NODE_FAIL", "OUT_OF_MEMORY", "PREEMPTED", "BOOT_FAIL",
            "DEADLINE")


class ClusterUnavailable(RuntimeError):
    """The cluster could not be started; the message says why."""


def present() -> bool:
    """Whether munge's and Slurm's daemons and commands are installed."""
    return all(shutil.which(program) for program in PROGRAMS)


@dataclass(frozen=True)
class Task:
    """One task of an array job, as ``scontrol show job`` last saw it."""

    job: int
    """Its own job id (the array's id is the first task's)."""
    index: int
    state: str
    exit_code: str
    """``STATUS:SIGNAL``, as Slurm writes it."""


@dataclass(frozen=True)
class Cluster:
    """A running single-node cluster: its folder, its configuration and its node's cores."""

    folder: Path
    config: Path
    cpus: int

    def environment(self, env: dict[str, str] | None = None) -> dict[str, str]:
        """This process's environment and ``env`` with SLURM_CONF set to the cluster's configuration."""
        return os.environ | (env or {}) | {"SLURM_CONF": str(self.config)}

    def run(self, *command: str, cwd: Path | None = None, env: dict[str, str] | None = None) -> str:
        """Run a Slurm command against this cluster, with ``env`` added to its environment; its output (raises,
        with its output, if it fails)."""
        done = subprocess.run(command, cwd=cwd, env=self.environment(env), capture_output=True, text=True,
                              timeout=60)
        if done.returncode != 0:
            raise AssertionError(f"{' '.join(command)} exited with {done.returncode}: {done.stdout}{done.stderr}")
        return done.stdout

    def sbatch(self, script: Path, *options: str, env: dict[str, str] | None = None) -> int:
        """Submit ``script`` from its folder, where its output files go, with ``env`` added to the environment
        that its jobs get (sbatch passes on the submitter's); the job's (the array's) id."""
        return int(self.run("sbatch", "--parsable", *options, script.name, cwd=script.parent, env=env)
                   .strip().split(";")[0])

    def tasks(self, job: int) -> dict[int, Task]:
        """Array index -> the task, of the array ``job`` (a job that is no array has index 0)."""
        found = {}
        for line in self.run("scontrol", "--oneliner", "show", "job", str(job)).splitlines():
            fields = dict(re.findall(r"(\w+)=(\S*)", line))
            index = int(fields.get("ArrayTaskId", "0")) if fields.get("ArrayTaskId", "0").isdigit() else -1
            found[index] = Task(int(fields["JobId"]), index, fields["JobState"], fields["ExitCode"])
        return found

    def wait(self, job: int, timeout: float) -> dict[int, Task]:
        """Wait until every task of ``job`` has finished; its tasks (raises after ``timeout`` seconds)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            tasks = self.tasks(job)
            if -1 not in tasks and all(task.state in FINISHED for task in tasks.values()):
                return tasks
            time.sleep(1)
        raise AssertionError(f"job {job} did not finish within {timeout:g} s: {self.tasks(job)}\n"
                             f"{self.run('squeue', '--all', '--long')}")


def _stop(process: subprocess.Popen) -> None:
    if process.poll() is None:
        process.send_signal(signal.SIGTERM)
        try:
            process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def _tail(path: Path, lines: int = 30) -> str:
    return "\n".join(path.read_text(errors="replace").splitlines()[-lines:]) if path.exists() else ""


def _memory_mib() -> int:
    """This machine's memory in MiB, less a little, as slurmd would report it."""
    for line in Path("/proc/meminfo").read_text().splitlines():
        if line.startswith("MemTotal:"):
            return int(line.split()[1]) // 1024 - 256
    return 1024


def configuration(folder: Path, cpus: int, ports: tuple[int, int]) -> str:
    """The cluster's slurm.conf: one node of ``cpus`` cores in one partition, no accounting, no cgroups
    (processes tracked by parentage), every file in ``folder``."""
    return "\n".join([
        "ClusterName=elk-test",
        f"SlurmctldHost={socket.gethostname().split('.')[0]}(127.0.0.1)",
        f"SlurmctldPort={ports[0]}", f"SlurmdPort={ports[1]}",
        "SlurmUser=root", "SlurmdUser=root",
        "AuthType=auth/munge", "CredType=cred/munge", f"AuthInfo=socket={folder / 'munge.socket'}",
        f"StateSaveLocation={folder / 'state'}", f"SlurmdSpoolDir={folder / 'spool'}",
        f"SlurmctldPidFile={folder / 'slurmctld.pid'}", f"SlurmdPidFile={folder / 'slurmd.pid'}",
        f"SlurmctldLogFile={folder / 'slurmctld.log'}", f"SlurmdLogFile={folder / 'slurmd.log'}",
        "ProctrackType=proctrack/linuxproc", "TaskPlugin=task/none", "JobAcctGatherType=jobacct_gather/none",
        "AccountingStorageType=accounting_storage/none", "JobCompType=jobcomp/none", "SwitchType=switch/none",
        "MpiDefault=none", "SchedulerType=sched/builtin", "SelectType=select/cons_tres",
        "SelectTypeParameters=CR_CPU", "SlurmdParameters=config_overrides", "ReturnToService=2",
        "MinJobAge=3600", "KillWait=5",
        f"NodeName={NODE} NodeAddr=127.0.0.1 CPUs={cpus} RealMemory={_memory_mib()} State=UNKNOWN",
        f"PartitionName=main Nodes={NODE} Default=YES MaxTime=INFINITE State=UP",
    ]) + "\n"


@contextlib.contextmanager
def running_cluster() -> Iterator[Cluster]:
    """Start munged, slurmctld and slurmd on 127.0.0.1 in a new folder; yield the Cluster, idle."""
    from postgres_server import free_port

    missing = [program for program in PROGRAMS if not shutil.which(program)]
    if missing:
        raise ClusterUnavailable(f"{', '.join(missing)} not found: install Debian's slurm-wlm and munge")
    if os.geteuid() != 0:
        raise ClusterUnavailable("slurmd runs jobs as the user who submits them, which needs root")
    # munged wants every folder above its socket open to all (it is root's; nothing secret is in it but the
    # key, which is 0600)
    folder = Path(tempfile.mkdtemp(prefix="elk-slurm-"))
    folder.chmod(0o755)
    daemons: list[subprocess.Popen] = []
    cluster = Cluster(folder, folder / "slurm.conf", os.cpu_count() or 1)
    try:
        for name in ("state", "spool"):
            (folder / name).mkdir()
        key = folder / "munge.key"
        key.write_bytes(os.urandom(128))
        key.chmod(0o600)

        def start(name: str, *command: str) -> None:
            with open(folder / f"{name}.out", "w") as out:
                daemons.append(subprocess.Popen(command, cwd=folder, env=cluster.environment(), stdout=out,
                                                stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                                start_new_session=True))

        socket_path = folder / "munge.socket"
        start("munged", "munged", "--foreground", f"--socket={socket_path}", f"--key-file={key}",
              f"--pid-file={folder / 'munged.pid'}", f"--log-file={folder / 'munged.log'}",
              f"--seed-file={folder / 'munged.seed'}")
        _wait_for(socket_path.exists, daemons, "munged did not create its socket", folder / "munged.out")
        cluster.config.write_text(configuration(folder, cluster.cpus, (free_port(), free_port())))
        start("slurmctld", "slurmctld", "-D", "-f", str(cluster.config))
        start("slurmd", "slurmd", "-D", "-N", NODE, "-f", str(cluster.config))

        def idle() -> bool:
            done = subprocess.run(["sinfo", "--noheader", "--format=%t"], env=cluster.environment(),
                                  capture_output=True, text=True, timeout=30)
            return done.returncode == 0 and done.stdout.strip() == "idle"

        _wait_for(idle, daemons, "the node did not become idle", folder / "slurmctld.log", folder / "slurmd.log")
        yield cluster
    finally:
        if len(daemons) == 3:
            subprocess.run(["scancel", "--full", "--user", str(os.getuid())], env=cluster.environment(),
                           capture_output=True, timeout=60)
            with contextlib.suppress(ClusterUnavailable):
                _wait_for(lambda: not subprocess.run(["squeue", "--noheader"], env=cluster.environment(),
                                                     capture_output=True, text=True, timeout=30).stdout.strip(),
                          daemons, "jobs were left")
        for daemon in reversed(daemons):
            _stop(daemon)
        shutil.rmtree(folder, ignore_errors=True)


def _wait_for(ready: Callable[[], bool], daemons: list[subprocess.Popen], what: str, *logs: Path) -> None:
    """Wait until ``ready()``; raise ClusterUnavailable saying ``what``, with the end of each log, if one of the
    ``daemons`` exits or after START_TIMEOUT."""
    deadline = time.monotonic() + START_TIMEOUT
    while time.monotonic() < deadline:
        if ready():
            return
        if any(daemon.poll() is not None for daemon in daemons):
            break
        time.sleep(0.5)
    raise ClusterUnavailable("\n".join([f"{what}:", *map(_tail, logs)]))

"""README's Slurm array (Large classes), run as written on a real single-node Slurm (tests/slurm_cluster.py)
against a real PostgreSQL gradebook (tests/postgres_server.py), with only the substitutions README lists.

The class: four of the demo's train-kf submissions, the quickest lab (the blank, a cheat, a fault and
the solved notebook), two in each of two shards, each task one core. Its baseline is one
`grade --jobs 1` into a fresh gradebook, exported. The array's tasks complete, each with a log of its
own, and its export equals the baseline, row for row. Then task 1 is rerun as README says (`sbatch
--array=1 grade.sh`) and cancelled (`scancel JOB_1`) while it grades a submission: the export fails and
names that submission; rerun once more, the export equals the baseline again, and every run of task 1
kept its log. Each submission is graded four times: 2.8 minutes on two cores beside a benchmark.

It needs Debian's slurm-wlm and munge, and root (slurmd runs jobs as their user): without them it is
skipped on a user's machine and fails in CI (tests/machine_needs.py).
"""

from __future__ import annotations

import re
import shutil
import time
from pathlib import Path

import pytest
from sqlalchemy.engine import make_url

import shard_runs
from postgres_server import postgres_url  # noqa: F401 (a fixture: this module's own server)
from slurm_cluster import Cluster, ClusterUnavailable, running_cluster
from autograder.catalogues import demo
from autograder.labs import ROOT, get_lab
from autograder.pipeline.nbgrader_apps import feedback_page
from autograder.pipeline.shards import Shard

pytestmark = pytest.mark.needs("slurm", "root")

LAB = get_lab("train-kf")
SHARDS = 2


@pytest.fixture(scope="module")
def cluster():
    """A single-node Slurm of this module's own; without one the test fails, saying why."""
    reason = None
    try:
        with running_cluster() as running:
            yield running
    except ClusterUnavailable as error:
        reason = str(error)
    if reason:
        pytest.fail(reason, pytrace=False)


def readme_script() -> str:
    """README's Slurm array script: the code block after "A Slurm array of"."""
    readme = (ROOT / "README.md").read_text()
    return re.search(r"A Slurm array of .*?```\n(.*?)```", readme, re.S).group(1)


def substituted(script: str, substitutions: dict[str, str]) -> str:
    """``script`` with each text replaced, every one of which must be there (README and the test agree)."""
    for old, new in substitutions.items():
        assert old in script, f"README's Slurm script no longer has {old!r}: update README's list and this test"
        script = script.replace(old, new)
    return script


def write_array(folder: Path, klass: Path, db_url: str, cpus: int) -> Path:
    """README's script, with what README says to adapt, as ``folder/grade.sh``, and a password file for
    the gradebook's URL (README: "password in ~/.pgpass"; libpq reads $PGPASSFILE, which sbatch passes on).
    The paths, the URL, N (8, twice) and the cores a task asks for."""
    url = make_url(db_url)
    folder.mkdir()
    script = substituted(readme_script(), {
        "/shared/estimation-lab-kit": str(ROOT),
        "postgresql+psycopg://grader@db.example.org:5432/course":
            url.set(password=None).render_as_string(hide_password=False),
        "/shared/submissions": str(klass),
        "/shared/course": str(folder / "course"),
        "--array=1-8": f"--array=1-{SHARDS}",
        '/8"': f'/{SHARDS}"',
        "--cpus-per-task=16": f"--cpus-per-task={cpus}",
    })
    (folder / "grade.sh").write_text(script)
    pgpass = folder / "pgpass"
    pgpass.write_text(f"{url.host}:{url.port}:*:{url.username}:{url.password}\n")
    pgpass.chmod(0o600)
    return folder / "grade.sh"


def submit(cluster: Cluster, script: Path, *options: str) -> int:
    return cluster.sbatch(script, *options, env={"PGPASSFILE": str(script.parent / "pgpass")})


def states(tasks) -> dict[int, tuple[str, str]]:
    return {index: (task.state, task.exit_code) for index, task in tasks.items()}


def small_class(folder: Path) -> dict[tuple[str, str], object]:
    """Four of the demo's six train-kf submissions, two in each shard (the first two of each by name):
    (student, lab) -> its catalogued outcome."""
    outcomes = demo.write_demo_class([LAB], folder)
    kept = [s for k in range(1, SHARDS + 1) for s in sorted(s for s, _ in outcomes if Shard(k, SHARDS).takes(s))[:2]]
    for student in {s for s, _ in outcomes} - set(kept):
        shutil.rmtree(folder / student)
    return {key: outcome for key, outcome in outcomes.items() if key[0] in kept}


def test_readmes_slurm_array_grades_as_one_process_and_a_cancelled_task_rerun_completes_the_class(
        cluster, postgres_url, tmp_path):
    klass = tmp_path / "class"
    outcomes = small_class(klass)
    baseline_url = shard_runs.new_database(postgres_url, "baseline")
    shard_runs.start_grade(klass, tmp_path / "baseline", baseline_url, tmp_path / "baseline.log",
                           "--jobs", "1").finish()
    exported = shard_runs.export(tmp_path / "baseline", baseline_url)
    assert exported.returncode == 0, exported.stderr
    baseline = shard_runs.csv_rows(tmp_path / "baseline" / "grades.csv")
    assert len(baseline) == 1 + len(outcomes) == 1 + 2 * SHARDS

    # the array as written: every task completes, each with a log of its own, and the export is the baseline's
    url = shard_runs.new_database(postgres_url, "array")
    script = write_array(tmp_path / "array", klass, url, max(1, cluster.cpus // SHARDS))
    course = script.parent / "course"
    job = submit(cluster, script)
    done = cluster.wait(job, timeout=900)
    logs = {path.name: path.read_text() for path in script.parent.glob("grade-*.log")}
    assert states(done) == {k: ("COMPLETED", "0:0") for k in range(1, SHARDS + 1)}, logs
    assert sorted(logs) == [f"grade-{job}_{k}.log" for k in range(1, SHARDS + 1)]
    assert all(f"Shard {k}/{SHARDS} grades 2 submissions of the class's 4." in logs[f"grade-{job}_{k}.log"]
               for k in range(1, SHARDS + 1))
    exported = shard_runs.export(course, url)
    assert exported.returncode == 0, exported.stderr
    assert shard_runs.csv_rows(course / "grades.csv") == baseline

    # task 1 again, as README reruns a task, cancelled (scancel) while it grades a submission: nbgrader has
    # removed that submission's graded notebook, so the export fails and names it; rerun, the class is whole
    victim, theirs = 1, sorted(key for key in outcomes if Shard(1, SHARDS).takes(key[0]))

    def being_graded() -> list[tuple[str, str]]:
        return [(s, lab) for s, lab in theirs
                if not (course / "autograded" / s / lab / get_lab(lab).notebook_name).exists()]

    assert "sbatch --array=3 grade.sh" in (ROOT / "README.md").read_text()  # how README reruns task 3
    cancelled = submit(cluster, script, f"--array={victim}")
    deadline = time.monotonic() + 600
    while not being_graded() and time.monotonic() < deadline:
        time.sleep(0.05)
    cluster.run("scancel", f"{cancelled}_{victim}")
    assert [task.state for task in cluster.wait(cancelled, timeout=300).values()] == ["CANCELLED"]
    cut_short = shard_runs.export(course, url)
    assert cut_short.returncode == 1
    listed = {tuple(line.split(":")[0].split()) for line in cut_short.stderr.splitlines() if line.startswith("  ")}
    assert listed == set(being_graded()) and 0 < len(listed) < len(outcomes), cut_short.stderr

    rerun = submit(cluster, script, f"--array={victim}")
    assert states(cluster.wait(rerun, timeout=900)) == {victim: ("COMPLETED", "0:0")}
    exported = shard_runs.export(course, url)
    assert exported.returncode == 0, exported.stderr
    assert shard_runs.csv_rows(course / "grades.csv") == baseline
    kept = sorted(path.name for path in script.parent.glob(f"grade-*_{victim}.log"))
    assert kept == sorted(f"grade-{j}_{victim}.log" for j in (job, cancelled, rerun))  # no log overwritten

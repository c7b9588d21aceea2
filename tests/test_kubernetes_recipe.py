"""The Kubernetes recipe (deploy/kubernetes/): its manifests parse, and hold what lets them run (issue 35).

No cluster is reachable from the tests, and no container runtime runs here: these checks read the files.
The manifests also passed `kubernetes-validate --strict` (PyPI) against Kubernetes 1.30 to 1.37, run by
hand (deploy/kubernetes/README.md). Checked here: the grading Job is Indexed with N pods for
`--shard $((JOB_COMPLETION_INDEX + 1))/N`, retries each index on its own, ends after the Slurm
script's time, refuses a partial sandbox and lets the sandbox make its namespaces; a pod's cores fit
a 16-vCPU node and equal its `--jobs`, its memory limit is 4 GiB per kernel and 4 GiB more, and its
scratch is ephemeral storage; the export Job reads what the shards wrote; the image runs as a user who
is not root; the secret's command makes a URL that gives back the password; README's rerun of one
shard makes the Job it says.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess

import pytest
import yaml
from sqlalchemy.engine import make_url

from autograder.labs import ROOT
from autograder.pipeline.grading_secret import ENVIRONMENT_VARIABLE

RECIPE = ROOT / "deploy" / "kubernetes"
GIB = 2**30
UNITS = {"Ki": 2**10, "Mi": 2**20, "Gi": GIB, "Ti": 2**40, "m": 1e-3, "": 1}


def quantity(text: str | int) -> float:
    """A Kubernetes quantity ("28Gi", "14", "500m") as a number (bytes, cores)."""
    number, unit = re.fullmatch(r"([\d.]+)([A-Za-z]*)", str(text)).groups()
    return float(number) * UNITS[unit]


def manifest(name: str) -> dict:
    return yaml.safe_load((RECIPE / name).read_text())


def pod(job: dict) -> tuple[dict, dict]:
    """The Job's pod spec and its one container."""
    spec = job["spec"]["template"]["spec"]
    assert len(spec["containers"]) == 1
    return spec, spec["containers"][0]


def command(container: dict) -> list[str]:
    """The container's command, as the shell splits its `sh -c` script."""
    assert container["command"][:2] == ["sh", "-c"]
    return shlex.split(container["command"][2])


def option(words: list[str], name: str) -> str:
    return words[words.index(name) + 1]


def slurm_seconds() -> int:
    hours, minutes, seconds = re.search(r"#SBATCH --time=(\d+):(\d+):(\d+)", (ROOT / "README.md").read_text()).groups()
    return int(hours) * 3600 + int(minutes) * 60 + int(seconds)


def image_user() -> int:
    return int(re.search(r"^USER (\d+)", (RECIPE / "Containerfile").read_text(), re.M).group(1))


def image_group() -> int:
    recipe = (RECIPE / "Containerfile").read_text()
    gid = re.search(r"^USER \d+:(\d+)$", recipe, re.M).group(1)
    assert f"groupadd --gid {gid} grader" in recipe
    return int(gid)


def test_the_grading_job_runs_one_shard_per_index_retried_on_its_own():
    job = manifest("grade-job.yaml")
    assert (job["apiVersion"], job["kind"]) == ("batch/v1", "Job")
    spec = job["spec"]
    words = command(pod(job)[1])
    assert words[:5] == ["exec", ".venv/bin/python", "-m", "autograder", "grade"]
    script = pod(job)[1]["command"][2]  # the shard's number is the shell's arithmetic, which shlex splits
    count = int(re.search(r" --shard \$\(\(JOB_COMPLETION_INDEX \+ 1\)\)/(\d+) ", script).group(1))
    assert spec["completionMode"] == "Indexed" and spec["completions"] == spec["parallelism"] == count
    assert spec["backoffLimitPerIndex"] >= 1 and "backoffLimit" not in spec  # not one budget for the whole Job
    assert pod(job)[0]["restartPolicy"] == "Never"  # which backoffLimitPerIndex requires
    assert spec["activeDeadlineSeconds"] == slurm_seconds()
    assert "--require-sandbox" in words and option(words, "--workdir") == "/shared/course"


def test_a_grading_pod_fits_a_16_vcpu_node_and_caps_its_kernels():
    spec, container = pod(manifest("grade-job.yaml"))
    requests, limits = container["resources"]["requests"], container["resources"]["limits"]
    jobs = int(option(command(container), "--jobs"))
    assert quantity(requests["cpu"]) == jobs <= 15  # a 16-vCPU node offers pods less than 16
    assert quantity(limits["memory"]) == jobs * 4 * GIB + 4 * GIB  # each kernel's 4 GiB cap, and the graders
    assert quantity(requests["memory"]) <= quantity(limits["memory"]) and quantity(requests["memory"]) <= 32 * GIB
    assert quantity(requests["ephemeral-storage"]) <= quantity(limits["ephemeral-storage"])
    scratch = next(m for m in container["volumeMounts"] if m["mountPath"] == "/tmp")["name"]
    volume = next(v for v in spec["volumes"] if v["name"] == scratch)
    assert quantity(volume["emptyDir"]["sizeLimit"]) <= quantity(limits["ephemeral-storage"])


def test_a_grading_pod_runs_as_the_images_user_and_lets_the_sandbox_make_its_namespaces():
    spec, container = pod(manifest("grade-job.yaml"))
    context = spec["securityContext"]
    assert context["runAsNonRoot"] is True and context["runAsUser"] == image_user() != 0
    assert context["runAsGroup"] == context["fsGroup"] == image_group()
    assert context["seccompProfile"]["type"] in ("Unconfined", "Localhost")  # RuntimeDefault forbids unshare()
    assert context["appArmorProfile"]["type"] in ("Unconfined", "Localhost")
    assert container["securityContext"]["allowPrivilegeEscalation"] is False
    assert container["securityContext"]["capabilities"]["drop"] == ["ALL"]
    secret = {"secretKeyRef": {"name": "gradebook", "key": "url"}}
    assert container["env"][0] == {"name": "GRADEBOOK_URL", "valueFrom": secret}
    assert spec["imagePullSecrets"]  # the image is in a private registry


@pytest.mark.parametrize("name", ["grade-job.yaml", "export-job.yaml"])
def test_every_pod_reads_the_one_grading_secret_from_a_kubernetes_secret(name):
    """The image holds no grading secret and its course root is read-only: grading there without
    KIT_GRADING_SECRET_FILE failed (tried as uid 10001, deploy/kubernetes/README.md)."""
    spec, container = pod(manifest(name))
    named = {e["name"]: e.get("value") for e in container["env"]}[ENVIRONMENT_VARIABLE]
    mount = next(m for m in container["volumeMounts"] if named.startswith(m["mountPath"] + "/"))
    volume = next(v for v in spec["volumes"] if v["name"] == mount["name"])
    assert volume["secret"]["secretName"] == "grading-secret" and mount["readOnly"] is True
    assert volume["secret"]["defaultMode"] & 0o040 and spec["securityContext"]["fsGroup"] == image_group()
    assert "kubectl create secret generic grading-secret --from-file=secret=" in (RECIPE / "README.md").read_text()


def test_the_export_job_reads_what_the_shards_wrote():
    grade_spec, grade = pod(manifest("grade-job.yaml"))
    job = manifest("export-job.yaml")
    spec, export = pod(job)
    assert job["spec"]["backoffLimit"] == 0 and job["spec"]["activeDeadlineSeconds"] > 0
    script = export["command"][2]
    assert ".venv/bin/python -m autograder export --workdir /shared/course" in script
    assert "autograder report --workdir /shared/course" in script
    assert option(command(grade), "--workdir") == "/shared/course"
    assert (export["image"], export["env"]) == (grade["image"], grade["env"])
    assert spec["volumes"][0] == grade_spec["volumes"][0]
    assert spec["securityContext"]["runAsUser"] == image_user() and spec["securityContext"]["runAsNonRoot"] is True


def test_the_image_installs_the_environment_holds_the_course_root_and_runs_as_a_user():
    recipe = (RECIPE / "Containerfile").read_text()
    assert re.search(r"^FROM \S*python:3\.11", recipe, re.M)
    assert "pip install --quiet -r environment.txt" in recipe
    copied = [word.rstrip("/") for line in re.findall(r"^COPY (.*) \S+$", recipe, re.M) for word in line.split()]
    assert {"solutions", "source", "autograder", "course", "environment.txt", "nbgrader_config.py"} <= set(copied)
    assert all((ROOT / path).exists() for path in copied), copied
    assert image_user() != 0 and "private registry" in recipe


def test_the_secrets_command_encodes_any_password(tmp_path):
    steps = (RECIPE / "README.md").read_text()
    script = re.search(r"^ *python3 -c '(.*?)'", steps, re.M).group(1)
    password = "p@ss:w/rd%20?#&'é"
    made = subprocess.run(["python3", "-c", script], env=os.environ | {"PASSWORD": password}, capture_output=True,
                          text=True, check=True).stdout
    url = make_url(made)
    assert (url.drivername, url.password, url.host, url.database) == (
        "postgresql+psycopg", password, "db.example.org", "course")
    assert "kubectl create secret generic gradebook --from-file=url=/dev/stdin" in steps


def test_readmes_rerun_of_one_shard_makes_a_job_of_that_shard():
    steps = (RECIPE / "README.md").read_text()
    sed = re.search(r"^   (sed .*?)\| kubectl apply -f -$", steps, re.M | re.S).group(1).replace("\\\n", " ")
    made = subprocess.run(sed, shell=True, cwd=ROOT, capture_output=True, text=True, check=True).stdout
    job = yaml.safe_load(made)
    assert job["metadata"]["name"] == "grade-shard-3"
    assert job["spec"]["completions"] == job["spec"]["parallelism"] == 1
    assert option(command(pod(job)[1]), "--shard") == "3/8"


@pytest.mark.parametrize("name", ["grade-job.yaml", "export-job.yaml"])
def test_the_manifests_hold_one_document_each(name):
    assert len(list(yaml.safe_load_all((RECIPE / name).read_text()))) == 1

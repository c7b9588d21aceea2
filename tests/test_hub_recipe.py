"""The JupyterHub recipe (deploy/jupyterhub/, issue 36).

The fast test: setup_hub.py refuses to start a hub while other users can read ``solutions/``.

The hub test starts the recipe's hub for real, as root (CI runs as root): a student and an instructor are
local users made for the test (and removed after it), the hub listens on a free loopback port, and
everything else (the course root, the hub's prefix with the exchange and the students' environment) is in a
temporary folder under /tmp that the test removes. The course root is the instructor's, mode 0700, with
train-kf released into it as ``nbgrader generate_assignment`` does; the instructor releases it through the
exchange with the hub's instructor configuration (the instructor's own server is not started: the formgrader
is in the recipe's real run, deploy/jupyterhub/README.md). The authenticator is the dummy one with a shared
password. In Chromium, the student logs in, finds train-kf in the Assignment List, fetches it, presses
Validate, and submits; the submission lands in the exchange's inbound folder. The student's Python imports
``course`` from its own site-packages and cannot import ``solutions``.
"""

from __future__ import annotations

import os
import pwd
import re
import secrets
import shutil
import socket
import subprocess
import sys
import tempfile
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from playwright.sync_api import expect

from autograder.labs import ROOT, get_lab
from autograder.pipeline import nbgrader_apps
from student_jupyterlab import chromium

SETUP = ROOT / "deploy" / "jupyterhub" / "setup_hub.py"
LAB = get_lab("train-kf")
COURSE = nbgrader_apps.course_config().CourseDirectory.course_id
WAIT_MS = 240_000  # the first start of a student's server on a loaded 2-core machine


def test_setup_refuses_while_others_can_read_solutions() -> None:
    folder = Path(tempfile.mkdtemp(prefix="kit-hub-refuses-", dir="/tmp"))
    try:
        course = folder / "course"
        (course / "solutions").mkdir(parents=True)
        for path in (folder, course, course / "solutions"):
            path.chmod(0o755)
        done = subprocess.run([sys.executable, str(SETUP), "--course-root", str(course), "--instructor", "nobody",
                               "--students", "nobody", "--prefix", str(folder / "hub"), "--setup-only"],
                              capture_output=True, text=True, cwd=ROOT)
        assert done.returncode == 1, done.stdout + done.stderr
        assert "OTHER USERS OF THIS MACHINE CAN READ" in done.stderr and str(course / "solutions") in done.stderr
        assert done.stderr.rstrip().endswith("The hub is not started."), done.stderr
        assert not (folder / "hub").exists(), "setup_hub.py set something up before it refused"
    finally:
        shutil.rmtree(folder)


@dataclass(frozen=True)
class Hub:
    url: str
    student: str
    password: str
    prefix: Path


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def answers(url: str) -> bool:
    try:
        with urllib.request.urlopen(f"{url}/hub/api", timeout=5) as response:
            return response.status == 200
    except OSError:
        return False


@pytest.fixture(scope="module")
def hub() -> Iterator[Hub]:
    tag = secrets.token_hex(3)
    instructor, student = f"kit-teacher-{tag}", f"kit-student-{tag}"
    folder = Path(tempfile.mkdtemp(prefix="kit-hub-", dir="/tmp"))
    folder.chmod(0o755)
    hub_process = None
    try:
        for name in (instructor, student):
            subprocess.run(["useradd", "--create-home", "--shell", "/bin/bash", name], check=True)
        course, prefix = folder / "course", folder / "hub"
        course.mkdir()
        nbgrader_apps.generate_release([LAB], course)
        subprocess.run(["chown", "--recursive", f"{instructor}:", str(course)], check=True)
        course.chmod(0o700)
        password, port = secrets.token_hex(8), free_port()
        url = f"http://127.0.0.1:{port}"
        # The instructor's server is not started here, so any Python that runs jupyterhub-singleuser passes the check.
        command = [sys.executable, str(SETUP), "--course-root", str(course), "--instructor", instructor,
                   "--students", student, "--prefix", str(prefix), "--port", str(port), "--authenticator", "dummy",
                   "--instructor-python", str(prefix / "user-env" / "bin" / "python")]
        with (folder / "hub.log").open("w") as log:
            hub_process = subprocess.Popen(command, env={**os.environ, "ELK_HUB_PASSWORD": password}, cwd=ROOT,
                                           stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        while not answers(url):
            assert hub_process.poll() is None, f"the hub stopped:\n{(folder / 'hub.log').read_text()[-3000:]}"
            try:
                hub_process.wait(timeout=1)
            except subprocess.TimeoutExpired:
                pass
        exchange = prefix / "exchange"
        # nbgrader releases only as the owner of the exchange's course folder; with the students' Python,
        # which the test's instructor can run (the test's own may be under /root, closed to them)
        env = {"PATH": "/usr/bin:/bin", "HOME": pwd.getpwnam(instructor).pw_dir,
               "JUPYTER_CONFIG_PATH": str(prefix / "config" / "instructor")}
        released = subprocess.run([str(prefix / "user-env" / "bin" / "python"), "-m", "nbgrader", "release_assignment",
                                   LAB.id], cwd=course, env=env, user=instructor, capture_output=True, text=True)
        assert released.returncode == 0, released.stdout + released.stderr
        assert (exchange / COURSE / "outbound" / LAB.id / LAB.notebook_name).is_file()
        yield Hub(url, student, password, prefix)
    finally:
        if hub_process is not None and hub_process.poll() is None:
            hub_process.terminate()  # JupyterHub stops the users' servers and the proxy
            try:
                hub_process.wait(timeout=60)
            except subprocess.TimeoutExpired:
                os.killpg(hub_process.pid, 9)
        for name in (instructor, student):
            subprocess.run(["userdel", "--remove", name], capture_output=True)
        shutil.rmtree(folder)


@pytest.mark.needs("configurable-http-proxy", "root")
def test_a_students_python_has_course_but_not_the_course_root(hub: Hub) -> None:
    probe = ("import course, importlib.util; print(course.__file__); "
             "print(importlib.util.find_spec('solutions'), importlib.util.find_spec('autograder'))")
    done = subprocess.run([str(hub.prefix / "user-env" / "bin" / "python"), "-I", "-c", probe], user=hub.student,
                          cwd="/", capture_output=True, text=True, check=True)
    where, hidden = done.stdout.splitlines()
    assert where.startswith(str(hub.prefix / "user-env" / "lib")), where
    assert hidden == "None None", hidden


@pytest.mark.needs("chromium", "configurable-http-proxy", "root")
def test_a_student_fetches_validates_and_submits_the_lab_in_jupyterlab_on_the_hub(hub: Hub, tmp_path: Path) -> None:
    expect.set_options(timeout=WAIT_MS)
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.set_default_timeout(WAIT_MS)
        try:
            page.goto(f"{hub.url}/hub/login")
            page.fill("#username_input", hub.student)
            page.fill("#password_input", hub.password)
            page.click("#login_submit")
            page.wait_for_url(re.compile(rf"/user/{hub.student}/lab"))
            menu = page.locator("#jp-MainMenu").get_by_role("menuitem", name="Nbgrader", exact=True)
            menu.click()
            offered = " ".join(page.locator(".lm-Menu .lm-Menu-itemLabel").all_text_contents())
            assert not re.search("Formgrader|Course List|Create Assignment", offered), offered
            page.locator(".lm-Menu").get_by_text("Assignment List", exact=True).click()
            released = page.locator("#released_assignments_list")
            expect(released).to_contain_text(LAB.id)
            released.get_by_role("button", name="Fetch").click()
            fetched = page.locator("#fetched_assignments_list")
            expect(fetched).to_contain_text(LAB.id)

            page.goto(f"{hub.url}/user/{hub.student}/lab/tree/{LAB.id}/{LAB.notebook_name}")
            page.locator(".jp-NotebookPanel-toolbar").get_by_role("button", name="Validate").click()
            dialog = page.locator(".jp-Dialog-body")
            expect(dialog).to_contain_text("gain_information_form")  # the first blank, not written yet
            assert "Success" not in dialog.text_content()
            page.locator(".jp-Dialog").get_by_role("button", name="Ok").click()

            menu.click()
            page.locator(".lm-Menu").get_by_text("Assignment List", exact=True).click()
            page.locator("#fetched_assignments_list").get_by_role("button", name="Submit").click()
            expect(page.locator("#submitted_assignments_list")).to_contain_text(LAB.id)
        finally:
            page.screenshot(path=tmp_path / "hub-student.png")
    inbound = list((hub.prefix / "exchange" / COURSE / "inbound").glob(f"{hub.student}+{LAB.id}+*/{LAB.notebook_name}"))
    assert len(inbound) == 1, inbound
    assert pwd.getpwuid(inbound[0].stat().st_uid).pw_name == hub.student

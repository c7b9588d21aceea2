"""A student's JupyterLab from a fresh student bundle, in headless Chromium, for the browser test.

``running_jupyterlab(folder)`` writes the student bundle into ``folder/bundle`` with
``python -m autograder bundle`` (as an instructor does), starts ``jupyter lab`` in the bundle's
root (as the bundle's README tells students) on a free loopback port with a random token, waits
until the server answers its own HTTP API, yields its address, and stops it on exit. Everything
per-user that Jupyter reads or writes (data, runtime, settings, workspaces, IPython) goes to
folders under ``folder``, so that the developer's home changes nothing and nothing is left there;
its configuration is the bundle's own ``jupyter_config``. The kernel imports the bundle's
``course`` package (PYTHONPATH is the bundle). It runs in the test's environment, the
instructor's, which also installs ``solutions`` and ``autograder``: test_release checks that the
bundle installed as students install it does not.

``chromium()`` launches Debian's ``chromium`` (``apt-get install chromium``; ``.ci/run`` installs
it) through Playwright: Playwright's own browser download is not available, so it is pointed at
that executable. The browser tests are marked ``needs("chromium")`` (tests/machine_needs.py): without
Chromium they are skipped on a user's machine, saying how to install it, and fail in CI.
"""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import shutil
import socket
import subprocess
import sys
import urllib.error
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from playwright.sync_api import Browser, sync_playwright

from autograder.release.bundle import JUPYTER_CONFIG
from autograder.labs import ROOT

START_TIMEOUT = 120.0  # seconds for JupyterLab to answer its HTTP API (a loaded 2-core CI machine)
POLL_INTERVAL = 0.25  # seconds between two requests to the API while the server starts
STOP_TIMEOUT = 30.0
CHROMIUM_HINT = "Install Debian's Chromium: apt-get install --no-install-recommends chromium"


@dataclass(frozen=True)
class JupyterLab:
    url: str
    """http://127.0.0.1:<port>, without a trailing slash."""
    token: str
    bundle: Path
    log: Path

    def lab_url(self, path: str) -> str:
        """The address that opens ``path`` (relative to the bundle's root) in JupyterLab."""
        return f"{self.url}/lab/tree/{path}?token={self.token}"


def chromium_executable() -> str:
    """Debian's Chromium: $CHROMIUM if set, else ``chromium`` on the PATH."""
    found = os.environ.get("CHROMIUM") or shutil.which("chromium")
    if not found:
        raise FileNotFoundError(f"No `chromium` on the PATH. {CHROMIUM_HINT}")
    return found


@contextlib.contextmanager
def chromium() -> Iterator[Browser]:
    """Headless Debian Chromium, driven by Playwright."""
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium_executable(), headless=True)
        try:
            yield browser
        finally:
            browser.close()


def write_bundle(out: Path) -> Path:
    """The student bundle, written by README's command ``python -m autograder bundle OUT``."""
    subprocess.run([sys.executable, "-m", "autograder", "bundle", str(out)], cwd=ROOT, check=True,
                   capture_output=True, text=True)
    return out


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _student_environment(bundle: Path, home: Path) -> dict[str, str]:
    """The environment of ``jupyter lab``: the test's own, with Jupyter's per-user folders under
    ``home``, the bundle's own Jupyter configuration (as its README tells students to start
    JupyterLab: ``JUPYTER_CONFIG_DIR=jupyter_config``), and only the bundle on PYTHONPATH."""
    env = dict(os.environ)
    folders = {
        "JUPYTER_DATA_DIR": "data",
        "JUPYTER_RUNTIME_DIR": "runtime",
        "JUPYTERLAB_SETTINGS_DIR": "lab-settings",
        "JUPYTERLAB_WORKSPACES_DIR": "lab-workspaces",
        "IPYTHONDIR": "ipython",
    }
    for variable, name in folders.items():
        (home / name).mkdir(parents=True, exist_ok=True)
        env[variable] = str(home / name)
    env["JUPYTER_CONFIG_DIR"] = str(bundle / JUPYTER_CONFIG)
    env["PYTHONPATH"] = str(bundle)
    # A student is asked once whether JupyterLab may fetch news; the toast would cover the cells
    # in the screenshots, so this user answers "never" in their own settings.
    notification = home / "lab-settings" / "@jupyterlab" / "apputils-extension" / "notification.jupyterlab-settings"
    notification.parent.mkdir(parents=True, exist_ok=True)
    notification.write_text(json.dumps({"fetchNews": "false", "checkForUpdates": False}))
    return env


def _tail(path: Path, lines: int = 30) -> str:
    return "\n".join(path.read_text(errors="replace").splitlines()[-lines:])


def _answers(url: str, token: str) -> bool:
    """Whether the server answers GET /api/status with 200 (it is up and accepts the token)."""
    request = urllib.request.Request(f"{url}/api/status", headers={"Authorization": f"token {token}"})
    try:
        with urllib.request.urlopen(request, timeout=5) as response:
            return response.status == 200
    except (urllib.error.URLError, ConnectionError, TimeoutError):
        return False


def _wait_until_ready(server: subprocess.Popen, url: str, token: str, log: Path) -> None:
    """Return once the server answers its API; raise if it exits or takes over START_TIMEOUT."""
    for _ in range(int(START_TIMEOUT / POLL_INTERVAL)):
        if _answers(url, token):
            return
        try:  # the pause between two requests, which also notices a server that exits
            code = server.wait(timeout=POLL_INTERVAL)
        except subprocess.TimeoutExpired:
            continue
        raise RuntimeError(f"JupyterLab exited with status {code} before it answered at {url}:\n{_tail(log)}")
    raise RuntimeError(f"JupyterLab did not answer at {url} within {START_TIMEOUT:g} s:\n{_tail(log)}")


def _stop(server: subprocess.Popen) -> None:
    """SIGTERM (JupyterLab shuts its kernels down), then SIGKILL to the whole process group."""
    if server.poll() is None:
        server.terminate()
        try:
            server.wait(timeout=STOP_TIMEOUT)
        except subprocess.TimeoutExpired:
            os.killpg(server.pid, 9)
            server.wait()


@contextlib.contextmanager
def running_jupyterlab(folder: Path) -> Iterator[JupyterLab]:
    """A fresh student bundle in ``folder/bundle`` and JupyterLab serving it (see the module's doc)."""
    bundle = write_bundle(folder / "bundle")
    port, token = _free_port(), secrets.token_hex(16)
    url = f"http://127.0.0.1:{port}"
    log = folder / "jupyterlab.log"
    command = [
        sys.executable, "-m", "jupyter", "lab", "--no-browser", "--allow-root",
        "--ServerApp.ip=127.0.0.1", f"--ServerApp.port={port}", "--ServerApp.port_retries=0",
        f"--IdentityProvider.token={token}",
    ]
    with log.open("w") as output:
        server = subprocess.Popen(command, cwd=bundle, env=_student_environment(bundle, folder / "home"),
                                  stdin=subprocess.DEVNULL, stdout=output, stderr=subprocess.STDOUT,
                                  start_new_session=True)
    try:
        _wait_until_ready(server, url, token, log)
        yield JupyterLab(url=url, token=token, bundle=bundle, log=log)
    finally:
        _stop(server)

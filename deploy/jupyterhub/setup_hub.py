"""Set up and start a single-machine JupyterHub for the course, of The Littlest JupyterHub's kind.

Run as root, with the kit's Python, from the instructor's course root (README: Running a course on
JupyterHub; deploy/jupyterhub/README.md)::

    sudo .venv/bin/python deploy/jupyterhub/setup_hub.py --instructor instructor --students alice,bob

It refuses to start the hub while other users of the machine can read the course's private files
(``autograder/private_paths.py``). Then it makes, under ``--prefix``: nbgrader's exchange, a students'
Python environment with the ``course`` package installed (never the course root), the students' and the
instructor's Jupyter configuration, and the hub's settings; and runs JupyterHub with
``deploy/jupyterhub/jupyterhub_config.py`` in the foreground (``--setup-only`` stops before).
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import os
import pwd
import shutil
import socket
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
KIT = HERE.parent.parent
sys.path.insert(0, str(KIT))

from autograder import private_paths  # noqa: E402
from autograder.release.bundle import REQUIREMENTS, write_bundle, write_jupyter_config  # noqa: E402

HUB_CONFIG = HERE / "jupyterhub_config.py"
SETTINGS = "hub.json"
"""The hub's settings under the prefix, which jupyterhub_config.py reads (root only: it may hold a password)."""
PASSWORD_VARIABLE = "ELK_HUB_PASSWORD"
"""The shared password of the dummy authenticator (local tests only), read from the environment."""
NO_NEWS = {"@jupyterlab/apputils-extension:notification": {"fetchNews": "false", "checkForUpdates": False}}
"""JupyterLab's settings in the students' environment: no question about Jupyter's news on every first login."""


class Refused(SystemExit):
    """The hub is not set up: the message says why and what to do."""

    def __init__(self, reason: str) -> None:
        super().__init__(f"{reason}\nThe hub is not started.")


def course_id() -> str:
    """The course id of the kit's nbgrader configuration."""
    from autograder.pipeline.nbgrader_apps import course_config

    return course_config().CourseDirectory.course_id


def refuse_exposed(course_root: Path) -> None:
    """Refuse while others can read ``solutions/``, ``source/`` or the gradebook of ``course_root``."""
    exposed = private_paths.exposed(course_root)
    if exposed:
        raise Refused(private_paths.warning(exposed))


def account(name: str) -> pwd.struct_passwd:
    try:
        return pwd.getpwnam(name)
    except KeyError:
        raise Refused(f"There is no user {name!r} on this machine. Add it with `useradd -m {name}`.") from None


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def run(command: list[str], **kwargs) -> subprocess.CompletedProcess:
    """Run ``command`` from ``/`` (a stray module in the working folder must not shadow the standard library)."""
    return subprocess.run(command, cwd="/", check=True, text=True, **kwargs)


def make_exchange(exchange: Path, course: str, instructor: pwd.struct_passwd) -> None:
    """nbgrader's exchange: the root is root's and open to all, as nbgrader's release insists (mode 777), with the
    sticky bit, so that only the instructor can remove their course folder; nbgrader's release makes
    ``inbound/`` (where students submit), ``outbound/`` and ``feedback/`` in it."""
    exchange.mkdir(parents=True, exist_ok=True)
    os.chown(exchange, 0, 0)
    exchange.chmod(0o1777)
    (exchange / course).mkdir(exist_ok=True)
    os.chown(exchange / course, instructor.pw_uid, instructor.pw_gid)
    (exchange / course).chmod(0o755)


def make_user_env(env: Path, base_python: str) -> Path:
    """The students' environment: the student bundle's requirements, this hub's JupyterHub, and the ``course``
    package installed from the bundle (a copy in site-packages: kernels never see the course root)."""
    if not private_paths.readable_by_others(Path(base_python).resolve()):
        raise Refused(f"Students cannot run {base_python} (it, or a folder above it, is closed to them). "
                      "Give --user-python a Python 3.11 that every user can run, such as Debian's /usr/bin/python3.")
    if not (env / "bin" / "python").exists():
        run([base_python, "-I", "-m", "venv", str(env)])
    with tempfile.TemporaryDirectory() as folder:
        bundle = write_bundle(Path(folder) / "bundle")
        requirements = [line for line in (bundle / REQUIREMENTS).read_text().splitlines()
                        if line and not line.startswith(("#", "-e"))]
        run([str(env / "bin" / "python"), "-I", "-m", "pip", "install", "--quiet", "--disable-pip-version-check",
             *requirements, f"jupyterhub=={importlib.metadata.version('jupyterhub')}", str(bundle)])
    overrides = env / "share" / "jupyter" / "lab" / "settings" / "overrides.json"
    overrides.parent.mkdir(parents=True, exist_ok=True)
    overrides.write_text(json.dumps(NO_NEWS) + "\n")
    return env / "bin" / "python"


def write_configs(config: Path, course_root: Path, exchange: Path, course: str) -> tuple[Path, Path]:
    """The students' and the instructor's Jupyter configuration folders (read-only for them: they come on
    JUPYTER_CONFIG_PATH, never as JUPYTER_CONFIG_DIR, where Jupyter writes)."""
    shutil.rmtree(config, ignore_errors=True)
    student, instructor = config / "student", config / "instructor"
    write_jupyter_config(student, exchange=True)
    exchange_lines = f"c.Exchange.root = {str(exchange)!r}\nc.CourseDirectory.course_id = {course!r}\n"
    with (student / "nbgrader_config.py").open("a") as file:
        file.write("\n# nbgrader's exchange on this hub (deploy/jupyterhub/setup_hub.py)\nc = get_config()  # noqa: F821\n"
                   + exchange_lines)
    instructor.mkdir(parents=True)
    (instructor / "nbgrader_config.py").write_text(
        "# The instructor's nbgrader on this hub (deploy/jupyterhub/setup_hub.py); the course root's own\n"
        "# nbgrader_config.py holds the course's settings.\nc = get_config()  # noqa: F821\n"
        f"c.CourseDirectory.root = {str(course_root)!r}\n" + exchange_lines)
    for path in [config, *config.rglob("*")]:
        path.chmod(0o755 if path.is_dir() else 0o644)
    return student, instructor


def check_instructor_python(python: Path, instructor: str) -> None:
    """The instructor's server runs in the kit's environment (the formgrader loads the course's configuration)."""
    tried = subprocess.run([str(python), "-I", "-c", "import jupyterhub.singleuser, nbgrader"], user=instructor,
                           cwd="/", capture_output=True, text=True)
    if tried.returncode:
        raise Refused(f"{instructor} cannot run JupyterHub's single-user server with {python}:\n{tried.stderr.strip()}\n"
                      "Make the course root's environment from a Python that the instructor can run (README's "
                      "first command, as the instructor), with jupyterhub installed, or name it with --instructor-python.")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--course-root", type=Path, default=KIT, help="the instructor's course root (default: this kit)")
    parser.add_argument("--instructor", required=True, help="the instructor's user name (owns the course root)")
    parser.add_argument("--students", required=True, help="the students' user names, comma-separated")
    parser.add_argument("--prefix", type=Path, default=Path("/opt/elk-hub"), help="where the hub keeps its files")
    parser.add_argument("--ip", default="127.0.0.1", help="the address the hub listens on")
    parser.add_argument("--port", type=int, default=8000)
    parser.add_argument("--authenticator", choices=("pam", "dummy"), default="pam",
                        help=f"pam: the users' system passwords; dummy: one shared password from ${PASSWORD_VARIABLE}, "
                             "for a test on 127.0.0.1 only")
    parser.add_argument("--user-python", default="/usr/bin/python3", help="the Python the students' environment is made from")
    parser.add_argument("--instructor-python", type=Path, help="default: the course root's .venv/bin/python")
    parser.add_argument("--setup-only", action="store_true", help="set up, but do not start the hub")
    args = parser.parse_args(argv)

    course_root = args.course_root.resolve()
    refuse_exposed(course_root)
    if os.geteuid() != 0:
        raise Refused("Run this as root: the hub starts each user's server as that user.")
    instructor = account(args.instructor)
    students = [name.strip() for name in args.students.split(",") if name.strip()]
    for name in students:
        account(name)
    if course_root.stat().st_uid != instructor.pw_uid:
        raise Refused(f"{course_root} is not {instructor.pw_name}'s. Give it to them: "
                      f"`chown -R {instructor.pw_name}: {course_root}`.")
    if args.authenticator == "dummy" and not os.environ.get(PASSWORD_VARIABLE):
        raise Refused(f"The dummy authenticator needs a password in ${PASSWORD_VARIABLE}.")

    os.umask(0o022)  # every user reads the students' environment and the configuration
    prefix = args.prefix.resolve()
    prefix.mkdir(parents=True, exist_ok=True)
    prefix.chmod(0o755)
    course = course_id()
    make_exchange(prefix / "exchange", course, instructor)
    user_python = make_user_env(prefix / "user-env", args.user_python)
    instructor_python = (args.instructor_python or course_root / ".venv" / "bin" / "python").absolute()
    check_instructor_python(instructor_python, instructor.pw_name)
    student_config, instructor_config = write_configs(prefix / "config", course_root, prefix / "exchange", course)
    state = prefix / "state"
    state.mkdir(exist_ok=True)
    state.chmod(0o700)
    settings = {
        "ip": args.ip, "port": args.port, "hub_port": free_port(), "proxy_api_port": free_port(), "state": str(state),
        "instructor": instructor.pw_name, "students": students, "course_root": str(course_root),
        "user_python": str(user_python), "instructor_python": str(instructor_python),
        "student_config": str(student_config), "instructor_config": str(instructor_config),
        "authenticator": args.authenticator, "password": os.environ.get(PASSWORD_VARIABLE, ""),
    }
    settings_file = prefix / SETTINGS
    settings_file.touch(mode=0o600)
    settings_file.chmod(0o600)
    settings_file.write_text(json.dumps(settings, indent=2) + "\n")
    print(f"Set up the hub in {prefix} for course {course}: {instructor.pw_name} teaches {', '.join(students)}.", flush=True)
    if not args.setup_only:
        os.chdir(state)
        os.environ["ELK_HUB_SETTINGS"] = str(prefix / SETTINGS)
        os.execv(sys.executable, [sys.executable, "-m", "jupyterhub", "-f", str(HUB_CONFIG)])


if __name__ == "__main__":
    main()

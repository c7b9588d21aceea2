"""JupyterHub configuration of the course's hub (deploy/jupyterhub/README.md).

setup_hub.py writes the settings (ports, users, environments, configuration folders) to the JSON file that
ELK_HUB_SETTINGS names and starts JupyterHub with this file. Each user's server runs as that local user
(LocalProcessSpawner): students in the students' environment, where ``course`` is installed, with the
students' read-only Jupyter configuration (Assignment List and Validate, no instructor tools); the
instructor in the course root's environment, in the course root, with the formgrader.
"""

import json
import os
from pathlib import Path

settings = json.loads(Path(os.environ["ELK_HUB_SETTINGS"]).read_text())
state = Path(settings["state"])
c = get_config()  # noqa: F821 (provided by traitlets when it loads this file)

c.JupyterHub.bind_url = f"http://{settings['ip']}:{settings['port']}"
c.JupyterHub.hub_ip = "127.0.0.1"
c.JupyterHub.hub_port = settings["hub_port"]
c.ConfigurableHTTPProxy.api_url = f"http://127.0.0.1:{settings['proxy_api_port']}"
c.ConfigurableHTTPProxy.pid_file = str(state / "proxy.pid")
c.JupyterHub.db_url = f"sqlite:///{state / 'jupyterhub.sqlite'}"
c.JupyterHub.cookie_secret_file = str(state / "jupyterhub_cookie_secret")
c.JupyterHub.pid_file = str(state / "jupyterhub.pid")

# Who may log in: PAM checks the users' system passwords; the dummy authenticator takes one shared password
# from anyone on the allowed list, which is only fit for a test on 127.0.0.1.
c.Authenticator.allowed_users = {settings["instructor"], *settings["students"]}
if settings["authenticator"] == "dummy":
    c.JupyterHub.authenticator_class = "dummy"
    c.DummyAuthenticator.password = settings["password"]
else:
    c.JupyterHub.authenticator_class = "pam"
    c.PAMAuthenticator.open_sessions = False

c.Spawner.default_url = "/lab"
c.Spawner.start_timeout = 180  # a server's first start on a loaded 2-core machine
c.Spawner.http_timeout = 120
# Only these variables of the hub's own environment reach a user's server: never PYTHONPATH, which could
# put the course root on a student kernel's path.
c.Spawner.env_keep = ["LANG", "LC_ALL"]


def role(spawner) -> None:
    """The student's or the instructor's server: its Python, folder and Jupyter configuration."""
    if spawner.user.name == settings["instructor"]:
        python, config = Path(settings["instructor_python"]), settings["instructor_config"]
        spawner.cmd = [str(python), "-m", "jupyterhub.singleuser"]
        spawner.notebook_dir = settings["course_root"]
    else:
        python, config = Path(settings["user_python"]), settings["student_config"]
        spawner.cmd = [str(python.parent / "jupyterhub-singleuser")]
        spawner.disable_user_config = True  # a student's own ~/.jupyter cannot bring the instructor tools back
    spawner.environment = {"JUPYTER_CONFIG_PATH": config,
                           "PATH": os.pathsep.join((str(python.parent), "/usr/local/bin", "/usr/bin", "/bin"))}


c.Spawner.pre_spawn_hook = role

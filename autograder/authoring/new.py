"""``python -m autograder new <lab>``: the files of a new lab, written from the template lab.

The template (``autograder/authoring/template/``, Jinja templates) is a tiny real lab: two blanks with
visible checks, hidden tests and catalogued mistakes with hints, a claim with its check, a cell whose
printed numbers nbval checks. Once built (``python -m autograder build <lab>``) it passes every test of
a lab, so a maintainer starts from green and edits it into the lab they want.
"""

from __future__ import annotations

import itertools
import keyword
import re
import tomllib
from datetime import datetime, timedelta
from pathlib import Path

import jinja2

from autograder.labs import DUE_DATES, ROOT, Lab

TEMPLATES = Path(__file__).parent / "template"
LAB_ID = re.compile(r"[a-z][a-z0-9]*(?:-[a-z0-9]+)*")
"""A lab id: lower-case words of letters and digits joined by hyphens, starting with a letter."""
HIDDEN_FILES = ("__init__.py", "draft.py", "reference.py", "hidden_tests.py", "mistakes.py", "alternatives.py",
                "mutants.py", "claims.py")
"""What ``new`` writes into ``solutions/<module>/``, each from ``template/<name>.j2``."""
README = ROOT / "README.md"
LABS_TABLE_HEADER = "| lab | topic | follows the handout |"
DUE_AFTER = timedelta(weeks=2)
"""A new lab is due this long after the last due date in ``due_dates.toml``."""
SUMMARY = "the template lab: a parcel's mass from readings of two scales, fused by their precisions"
"""The new lab's topic in README's table, until the maintainer writes the lab's own."""
NO_HANDOUT = "none: an original lab"
TEMPLATE = jinja2.Environment(loader=jinja2.FileSystemLoader(TEMPLATES), undefined=jinja2.StrictUndefined,
                              keep_trailing_newline=True, trim_blocks=True, lstrip_blocks=True)


def readme_labs() -> list[str]:
    """The lab ids that README's table of the labs lists, in its order (rows "| `<lab>` | ... |")."""
    lines = README.read_text().splitlines()
    rows = itertools.takewhile(lambda line: line.startswith("|"), lines[lines.index(LABS_TABLE_HEADER) + 2:])
    return [row.split("`")[1] for row in rows]


def _due_dates() -> dict[str, datetime]:
    """Lab id -> due date, as ``due_dates.toml`` has them (labs not built yet too)."""
    return tomllib.loads(DUE_DATES.read_text())["due"]


def refusals(lab_id: str, topic: str) -> list[str]:
    """Why ``new`` cannot write the lab ``lab_id`` with the course module ``course/<topic>.py`` (none: it can)."""
    if not LAB_ID.fullmatch(lab_id) or keyword.iskeyword(lab_id.replace("-", "_")):
        return [f"'{lab_id}' is not a lab id: lower-case words of letters and digits joined by hyphens, starting "
                "with a letter, such as scalar-kf."]
    lab, found = Lab(lab_id), []
    reference_tests = ROOT / "tests" / f"test_{lab.module}_reference.py"
    if lab.source_notebook.parent.exists() or lab.hidden_folder.exists() or reference_tests.exists():
        found.append(f"The lab {lab_id} exists already (source/{lab_id}/, solutions/{lab.module}/ or "
                     f"{reference_tests.relative_to(ROOT)}).")
    if lab_id in _due_dates() or lab_id in readme_labs():
        found.append(f"due_dates.toml or README's table of the labs has {lab_id} already.")
    if not topic.isidentifier() or not topic.islower() or keyword.iskeyword(topic):
        found.append(f"'{topic}' cannot name a Python module: use lower-case letters, digits and underscores.")
    elif (ROOT / "course" / f"{topic}.py").exists() or (ROOT / "course" / topic).exists():
        found.append(f"course/{topic}.py exists already: name the new lab's course module with --topic.")
    return found


def _add_due_date(lab: Lab) -> None:
    """Give the lab a due date in ``due_dates.toml``, DUE_AFTER after the last one, in its time zone."""
    due = f"{lab.id} = {(max(_due_dates().values()) + DUE_AFTER).isoformat()}\n"
    lines = DUE_DATES.read_text().splitlines(keepends=True)
    start = lines.index("[due]\n") + 1
    end = next((i for i in range(start, len(lines)) if lines[i].startswith("[")), len(lines))
    while end > start and not lines[end - 1].strip():
        end -= 1
    DUE_DATES.write_text("".join(lines[:end] + [due] + lines[end:]))


def _add_readme_row(lab: Lab) -> None:
    """Add the lab's row at the end of README's table of the labs."""
    lines = README.read_text().splitlines(keepends=True)
    end = lines.index(LABS_TABLE_HEADER + "\n") + 2 + len(readme_labs())
    lines.insert(end, f"| `{lab.id}` | {SUMMARY} | {NO_HANDOUT} |\n")
    README.write_text("".join(lines))


def new_lab(lab_id: str, topic: str | None = None, data: bool = False) -> list[Path]:
    """Write the files of the new lab ``lab_id`` from the template, and return them: its draft and hidden
    code in ``solutions/<module>/``, its course module ``course/<topic>.py`` (by default named for the
    lab's module), with ``data`` a data build in its reference and ``tests/test_<module>_reference.py``
    to prove the shipped data; and its due date and its row in README's table of the labs.

    Raises ValueError, saying why, if the id is not a lab id, the lab exists or the course module does.
    """
    lab = Lab(lab_id)
    topic = topic or lab.module
    problems = refusals(lab_id, topic)
    if problems:
        raise ValueError(" ".join(problems))
    files = {lab.hidden_folder / name: f"{name}.j2" for name in HIDDEN_FILES}
    files[ROOT / "course" / f"{topic}.py"] = "course.py.j2"
    if data:
        files[ROOT / "tests" / f"test_{lab.module}_reference.py"] = "test_reference.py.j2"
    lab.hidden_folder.mkdir(parents=True)
    for path, template in files.items():
        path.write_text(TEMPLATE.get_template(template).render(lab=lab.id, module=lab.module, topic=topic, data=data))
    _add_due_date(lab)
    _add_readme_row(lab)
    return [*files, DUE_DATES, README]

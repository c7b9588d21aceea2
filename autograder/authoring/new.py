"""``python -m autograder new <lab>``: the files of a new lab, written from the template lab.

The template (``autograder/authoring/template/``, Jinja templates) is a tiny real lab: two blanks with
visible checks, hidden tests and catalogued mistakes with hints, a claim with its check, a cell whose
printed numbers nbval checks, and a written answer with its model answer and rubric. Once built (``python -m autograder build <lab>``) it passes every test of
a lab, so a maintainer starts from green and edits it into the lab they want.
"""

from __future__ import annotations

import keyword
import re
import tomllib
from datetime import datetime, timedelta
from pathlib import Path

import jinja2
import jupytext

from autograder.labs import DUE_DATES, ROOT, Lab

TEMPLATES = Path(__file__).parent / "template"
LAB_ID = re.compile(r"[a-z][a-z0-9]*(?:-[a-z0-9]+)*")
"""A lab id: lower-case words of letters and digits joined by hyphens, starting with a letter."""
HIDDEN_FILES = ("__init__.py", "draft.py", "reference.py", "hidden_tests.py", "mistakes.py", "alternatives.py",
                "mutants.py", "claims.py")
"""What ``new`` writes into ``solutions/<module>/``, each from ``template/<name>.j2``."""
README = ROOT / "README.md"
README_ROW = "readme_row.md.j2"
"""The template of the new lab's row in README's table of the labs: the template lab's topic, until the
maintainer writes the lab's own (tests/test_template_text.py fails on a lab that keeps it)."""
DUE_AFTER = timedelta(weeks=2)
"""A new lab is due this long after the last due date in ``due_dates.toml``."""
TEMPLATE = jinja2.Environment(loader=jinja2.FileSystemLoader(TEMPLATES), undefined=jinja2.StrictUndefined,
                              keep_trailing_newline=True, trim_blocks=True, lstrip_blocks=True)


def table_cells(line: str) -> list[str]:
    """The cells of a row of a Markdown table, stripped (none: the line is no row)."""
    line = line.strip()
    return [cell.strip() for cell in line.strip("|").split("|")] if line.startswith("|") else []


def labs_table(lines: list[str]) -> range:
    """The indices, among README's ``lines``, of the rows of its table of the labs: the first table whose
    first column is headed "lab" (its other columns and their widths may change). Raises ValueError if
    README has none."""
    for at, line in enumerate(lines[:-1]):
        if table_cells(line)[:1] == ["lab"] and set("".join(table_cells(lines[at + 1]))) <= set("-:"):
            end = at + 2
            while end < len(lines) and table_cells(lines[end]):
                end += 1
            return range(at + 2, end)
    raise ValueError("README.md has no table of the labs: a Markdown table whose first column is headed 'lab'.")


def readme_rows() -> dict[str, list[str]]:
    """Lab id -> the cells of its row in README's table of the labs (``| `<lab>` | topic | handout |``), in
    the table's order; a lab listed twice keeps its last row (``readme_labs`` lists both)."""
    lines = README.read_text().splitlines()
    return {table_cells(lines[i])[0].strip("`"): table_cells(lines[i]) for i in labs_table(lines)}


def readme_labs() -> list[str]:
    """The lab ids that README's table of the labs lists, in its order (rows "| `<lab>` | ... |")."""
    lines = README.read_text().splitlines()
    return [table_cells(lines[i])[0].strip("`") for i in labs_table(lines)]


def _render(template: str, lab: Lab, topic: str, data: bool = False) -> str:
    return TEMPLATE.get_template(template).render(lab=lab.id, module=lab.module, topic=topic, data=data)


def template_row(lab: Lab) -> list[str]:
    """The cells of the row that ``new`` writes for ``lab`` in README's table of the labs."""
    return table_cells(_render(README_ROW, lab, lab.module))


def template_story(lab: Lab) -> list[str]:
    """The lines of the template lab's title and story, as ``new`` writes them for ``lab``: its first
    Markdown cell up to the first paragraph in bold ("**What you will do**"), blank lines left out."""
    draft = jupytext.reads(_render("draft.py.j2", lab, lab.module), fmt="py:percent")
    first = next(cell for cell in draft.cells if cell.cell_type == "markdown").source.splitlines()
    return [line for line in first[: next(i for i, line in enumerate(first) if line.startswith("**"))] if line.strip()]


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
    """Add the lab's row (README_ROW) at the end of README's table of the labs."""
    lines = README.read_text().splitlines(keepends=True)
    lines.insert(labs_table(lines).stop, _render(README_ROW, lab, lab.module))
    README.write_text("".join(lines))


def next_steps(lab: Lab, topic: str) -> str:
    """What a maintainer does after ``new`` wrote ``lab`` (with the course module ``course/<topic>.py``), in
    order, as ``new`` prints it: docs/adding-a-lab.md shows the same text (tests/test_new_lab.py)."""
    hidden = f"solutions/{lab.module}"
    steps = [
        f"python -m autograder build {lab.id}: the template lab's notebooks, which pass every test from here",
        f"edit course/{topic}.py: the model, the data and the figures that students are given",
        f"edit {hidden}/reference.py: the reference of every blank",
        f"edit {hidden}/draft.py: the story, the answer cells (the reference's code), the visible checks, the "
        "written answers",
        f"edit {hidden}/hidden_tests.py, then mistakes.py, alternatives.py, mutants.py and claims.py",
        f"edit {lab.id}'s row in README's table of the labs: its topic, and the handout it follows",
        f"python -m autograder build {lab.id}: again after each edit of the draft",
        f"python -m pytest --lab {lab.id} -n 2 --dist loadfile --nbval-lax",
    ]
    return "\n".join(["Next, in this order (docs/adding-a-lab.md):", *(f"  {n}. {step}" for n, step in enumerate(steps, 1))])


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
        path.write_text(_render(template, lab, topic, data))
    _add_due_date(lab)
    _add_readme_row(lab)
    return [*files, DUE_DATES, README]

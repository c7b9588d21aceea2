"""No lab keeps the template lab's text (issue 32 §4): ``python -m autograder new`` writes the template's
title and story into the new lab's notebook and its topic into README's table of the labs, for the
maintainer to replace, and every other test of a lab passes with them left in. tests/test_new_lab.py
checks that this file fails on a lab fresh from ``new``.
"""

from autograder import cells
from autograder.authoring.new import readme_rows, template_row, template_story
from over_labs import over_labs


@over_labs
def test_the_lab_keeps_none_of_the_template_labs_text(lab):
    markdown = "\n".join(c.source for c in cells.read(lab.source_notebook).cells if c.cell_type == "markdown")
    left = [f"the template's title or story in the notebook: {line!r}" for line in template_story(lab) if line in markdown]
    topic = template_row(lab)[1]
    if readme_rows()[lab.id][1] == topic:
        left.append(f"the template's topic in README's table of the labs: {topic!r}")
    assert not left, f"{lab.id} keeps text of the template lab; write the lab's own: {left}"

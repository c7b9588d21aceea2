"""The grader's output budget (autograder/pipeline/output_caps.py): a cap per cell and one per notebook."""

from nbformat.v4 import new_code_cell

from autograder.pipeline.output_caps import NOTED_LOUD_CELLS, OutputBudget


def test_a_cell_keeps_up_to_its_cap_and_says_once_that_it_dropped_the_rest():
    budget, cell = OutputBudget(per_cell=100, per_notebook=1000), new_code_cell()
    assert budget.room(0) == 100
    budget.count(cell, 0, size=60, kept=60)
    assert budget.room(0) == 40 and cell.outputs == []
    budget.count(cell, 0, size=70, kept=40)
    budget.count(cell, 0, size=5, kept=0)
    assert budget.room(0) == 0
    [line] = cell.outputs
    assert "kept the first 100 characters" in line.text
    assert budget.notes(str) == ["Cell 0 printed 135 characters; the grader kept the first 100."]


def test_the_notebook_cap_takes_room_from_every_later_cell():
    budget = OutputBudget(per_cell=100, per_notebook=150)
    budget.count(new_code_cell(), 0, size=100, kept=100)
    assert budget.room(1) == 50
    budget.count(new_code_cell(), 1, size=50, kept=50)
    assert budget.room(2) == 0
    assert budget.notes(str) == []


def test_the_notes_name_a_few_cut_cells_and_count_the_others():
    budget = OutputBudget(per_cell=10, per_notebook=10_000)
    loud = NOTED_LOUD_CELLS + 2
    for index in range(loud):
        budget.count(new_code_cell(), index, size=20, kept=10)
    budget.count(new_code_cell(), loud, size=5, kept=5)  # a quiet cell is not noted
    notes = budget.notes(lambda i: f"#{i}")
    assert notes[:NOTED_LOUD_CELLS] == [f"Cell #{i} printed 20 characters; the grader kept the first 10."
                                        for i in range(NOTED_LOUD_CELLS)]
    assert notes[NOTED_LOUD_CELLS:] == ["2 more cells printed more than the grader keeps: 10 characters of a "
                                        "cell's output, and 10,000 of the whole notebook's."]

"""What every lab's hidden tests use (the tests themselves are in ``solutions/<module>/hidden_tests.py``).

The test cell of blank ``f`` names ``check_f`` from its lab's hidden tests; the grader runs it in its
own process (autograder/pipeline/check_runner.py). Each check compares the student's function with the
reference on seeded random inputs, with every other blank bound to the reference (``isolate``), and
raises AssertionError with a message the student can act on. The notebooks hold no expected values,
because feedback shows students the test cells' code. Each check is decorated with
``diagnosis.diagnosed``: a failure whose results match one of the blank's catalogued mistakes ends
its message with that mistake's hint.
"""

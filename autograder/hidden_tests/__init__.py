"""Hidden tests, one module per lab (``hidden_tests/train_kf.py``).

The test cell of blank ``f`` calls ``check_f(f)`` from its lab's module in the grading kernel.
Each check compares the student's function with the reference on seeded random inputs, with every
other blank bound to the reference, and raises AssertionError with a message the student can act
on. The notebooks hold no expected values, because feedback shows students the test cells' code.
Each check is decorated with ``autograder.diagnosis.diagnosed``: a failure whose results match one
of the blank's catalogued mistakes ends its message with that mistake's hint.
"""

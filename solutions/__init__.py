"""Hidden reference solutions, one module per lab (``solutions.train_kf``, ...).

This package is for instructors and the grading kernel only. It is never installed and never
shipped to students.
"""

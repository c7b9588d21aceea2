"""Grading a class, in the order it happens.

- ``collect``: an LMS download becomes ``SUBMISSIONS/<student>/<lab>/<lab>.ipynb``;
- ``grading``: ``python -m autograder grade``, which runs the rest;
- ``nbgrader_apps``: nbgrader's converters, run in-process on a course folder;
- ``intake``: each submission read defensively into nbgrader's ``submitted/`` (``intake/`` for the course's own ``submitted/``);
- ``restore``: the lab's cells put back in order, and the grader's notes;
- ``execute``: nbgrader's execute step, made safe for a class (caps, recovery);
- ``hidden_blocks``: which check a graded test cell's hidden block names;
- ``check_runner``: that check, run in the grader's process against the student's function (``student_function``,
  over ``kernel_connection``; ``kernel_code`` installs the kernel's end);
- ``late``: due dates and the late penalty;
- ``grades``, ``table``, ``export``: the grades read back, printed and written to grades.csv;
- ``feedback``: the feedback pages; ``versions``: what the grades were graded with.
"""

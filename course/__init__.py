"""Support code for the Estimation Lab Kit labs.

Each module serves one lab and is named for what it holds (``course.train`` for the train
lab, ...). ``course.checks`` holds the check helpers that the visible tests use. Nothing here
implements a blank: the blanks are yours to write in the notebooks.
"""

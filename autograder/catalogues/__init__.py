"""What the kit grades to prove itself: plausible mistakes (``mistakes``; each lab's entries are in
``solutions/<module>/mistakes.py``), hostile submissions (``cheats``), careless ones (``faults``),
synthetic submissions and classes built from them (``submissions``, ``synthetic_class``), and the
demo that grades such a class (``demo``)."""

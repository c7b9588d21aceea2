"""Suspicious code in a submission: the scan that flags it for review (``scan``, with its syntax-tree
reader in ``visitor``), the step that takes away the points it games (``flag``), and the report
of answers that look copied (``similarity``)."""

"""The hidden code of the reentry-pf lab: ``reference``, ``hidden_tests``, ``mistakes``, ``claims``."""

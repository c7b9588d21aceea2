"""The hidden code of the reentry-srekf lab: ``reference``, ``hidden_tests``, ``mistakes``, ``claims``."""

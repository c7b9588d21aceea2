"""The hidden code of the nonlinear-filters lab: ``reference``, ``hidden_tests``, ``mistakes``, ``claims``."""

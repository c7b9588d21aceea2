"""The hidden code of the train-kf lab: ``reference``, ``hidden_tests``, ``mistakes``, ``claims``."""

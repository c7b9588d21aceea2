"""The hidden code of the castaway-bob lab: ``reference``, ``hidden_tests``, ``mistakes``, ``claims``. ``flow.py`` builds the ocean flow the lab ships (PhiFlow)."""

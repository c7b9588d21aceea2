"""What students get: the release notebooks (``notebooks``), the solution-free bundle (``bundle``), the
leak checks both pass (``leaks``), and the shipped data rebuilt from the reference (``data``)."""

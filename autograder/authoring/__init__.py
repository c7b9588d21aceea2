"""Writing and checking a lab: the lab's inventory (``inventory``) and the registry of its claims
(``claims``)."""

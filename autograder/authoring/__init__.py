"""Writing and checking a lab: a new lab from the template lab (``new``, ``template/``), the notebook made
from its draft (``build``), the lab's inventory (``inventory``) and the registry of its claims (``claims``)."""

"""The grading kernel: what runs inside it (``server``: the kernel's end of a hidden test; ``wire``:
the protocol both ends speak), the sandbox it runs in (``sandbox``) and the kernel manager that starts
it there (``manager``)."""

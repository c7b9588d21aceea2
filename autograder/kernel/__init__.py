"""The grading kernel: what runs inside it (``side``: the student's end of a hidden test and the
wire both ends speak), the sandbox it runs in (``sandbox``) and the kernel manager that starts it
there (``manager``)."""

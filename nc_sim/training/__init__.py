"""Training: exercises (a file format), their objective checks on a live machine, and the
score. Pure code: no I/O, no clock; the service reads the files and feeds the monitors."""

"""Inbetrieb's simulated NC: pure, deterministic, cycle-exact. No I/O, no clock."""

"""Commissioning assistants [004 §3.4-§3.6, 000 §2.2.4, §2.8.4]: the arithmetic a commissioning
engineer does on paper, and the experiments behind it, as pure procedures.

A calculator takes its inputs and answers; an experiment drives a machine (nc_sim.machine)
through a scripted motion in simulated time and analyses what it recorded. Both answer with a
`Result` (nc_sim/assist/result.py): the figures they measured or computed, the parameter
changes they propose (before and after, with why), and the series a plot shows.
"""

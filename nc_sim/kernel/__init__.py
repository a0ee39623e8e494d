"""The vectorised kernel: `arrays.Kernel` owns the state of every axis slot of every machine
and runs the one compiled step (`step.py`, numba). `layout` names the columns and imports
nothing compiled, so readers of kernel records (the signal table) need no numba."""

"""One simulated machine: its axes, spindles, channel, PLC and service readouts composed."""

"""Single-axis motion: the axis' runtime state and kernel row, jog, moves, homing, limits,
and the watchdog bounding each phase."""

"""Setpoint profiles: step-shaped, trapezoidal, sine-square and HSC [002 §2.2]."""

"""The spindle: M3/M4/M5, M19, G74, gear stages M40-M45, acceleration curves and the
changeover between position and speed control."""

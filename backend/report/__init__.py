"""The commissioning report: HTML with inline SVG plots, and its PDF."""

"""Benchmark scripts that print figures (run them as files: python bench/<name>.py)."""

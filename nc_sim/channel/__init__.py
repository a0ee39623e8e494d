"""The NC channel: interpreter (text -> canonical calls) and, later, block queue and path."""

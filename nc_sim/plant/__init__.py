"""What the NC drives: the drive cascade and the mechanics (model, compiled step, frequency
responses)."""

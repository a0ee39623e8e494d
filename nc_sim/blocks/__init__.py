"""Parsing NC blocks (MDI now, programs later) into commands."""

from nc_sim.blocks.mdi import Block, BlockError, SpindleCmd, parse_block

__all__ = ["Block", "BlockError", "SpindleCmd", "parse_block"]

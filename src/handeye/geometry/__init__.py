"""Rotations, rigid transforms and the checkerboard's description (numpy and scipy)."""

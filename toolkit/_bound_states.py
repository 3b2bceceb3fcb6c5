"""The pre-filter's answers per configuration (:mod:`toolkit._bound_kernels`)."""

CLOSE, FREE, HIT = 0, 1, 2
"""Undecided (coal decides), certainly free, certainly colliding."""

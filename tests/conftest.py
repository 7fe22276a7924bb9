"""Shared fixtures. Reference numbers live in tests/reference.py, copied from
shared/DESIGN.md section 5 and the seed paper, never produced by our code."""

"""Shared fixtures. Reference numbers live in tests/reference.py, computed before any
code existed (docs/method.md) or copied from the seed paper, never produced by our code."""

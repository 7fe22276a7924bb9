"""The simulated HP 35660A: command interpreter, physics and its front ends."""

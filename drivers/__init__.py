"""Transports (pyvisa / pyvisa-py, pyserial Prologix) and the HP 35660A driver.

Knows bytes and commands, nothing about HDF5 or beams."""

"""Transports (pyvisa / pyvisa-py, pyserial Prologix) and the driver of the HP dynamic
signal analyzer family (35660A, 3562A, 35665A/35670A: drivers/family.py).

Knows bytes and commands, nothing about HDF5 or beams."""

import logging

# A library's warnings (retries, recoveries) belong to the application's logging
# set-up: without a handler of our own, Python's last resort would print them on
# a notebook's stderr.
logging.getLogger("drivers").addHandler(logging.NullHandler())

"""The application: the `daq` command line, capture workflow and the run store."""

__version__ = "0.1.0"

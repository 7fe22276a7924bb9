"""The one error the run store raises: a one-line message naming the file or run.

The command line (daq/cli/errors.py) turns a StoreError into ``daq: error: ...`` and
exit status 1, and the service into an HTTP answer, so every store failure (bad id,
damaged file, full disk, bad config) reaches the user as one sentence, never as an h5py
traceback. The error is the store's own: the store knows nothing of the command line.
"""

from __future__ import annotations


class StoreError(Exception):
    """A run store failure with a one-line message (exit status 1 at the command line)."""

    exit_code = 1

    def __init__(self, message: str) -> None:
        # Messages must stay on one line: the CLI prints them after "daq: error: ".
        super().__init__(" ".join(str(message).split()))


class ConfigError(StoreError):
    """The configuration file exists but cannot be used (bad TOML, wrong type)."""


class NotARunError(StoreError):
    """An HDF5 file that is not a run of the store at all (no ``schema`` attribute on
    its root), as opposed to a run that is damaged: a caller that also reads other
    HDF5 layouts (replay's minimal files) tells the two apart by this class."""

"""The one error the run store raises: a one-line message naming the file or run.

The command line turns a :class:`daq.errors.UserError` into ``daq: error: ...`` and
exit status 1, so every store failure (bad id, damaged file, full disk, bad config)
reaches the user as one sentence, never as an h5py traceback.
"""

from __future__ import annotations

from daq.errors import UserError


class StoreError(UserError):
    """A run store failure with a one-line message (exit status 1)."""

    def __init__(self, message: str) -> None:
        # Messages must stay on one line: the CLI prints them after "daq: error: ".
        super().__init__(" ".join(str(message).split()), exit_code=1)


class ConfigError(StoreError):
    """The configuration file exists but cannot be used (bad TOML, wrong type)."""


class NotARunError(StoreError):
    """An HDF5 file that is not a run of the store at all (no ``schema`` attribute on
    its root), as opposed to a run that is damaged: a caller that also reads other
    HDF5 layouts (replay's minimal files) tells the two apart by this class."""

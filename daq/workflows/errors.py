"""The error the workflows raise: a one-line message and the exit status it stands for.

A :class:`WorkflowError` is a step of a workflow the user can put right (a run
file with no hits to replay, stored settings that do not fit, bad model inputs).
It belongs to this layer, not to the command line's: daq/cli/errors.py turns it
into ``daq: error: ...`` and its ``exit_code``.
"""

from __future__ import annotations


class WorkflowError(Exception):
    """A workflow failure with a one-line message.

    ``exit_code`` follows sysexits loosely, as the command line's UserError does: 1 for
    most, 2 for bad usage.
    """

    def __init__(self, message: str, exit_code: int = 1) -> None:
        # Messages must stay on one line: the CLI prints them after "daq: error: ".
        super().__init__(" ".join(str(message).split()))
        self.exit_code = exit_code

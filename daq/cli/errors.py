"""What the command line makes of the layers' errors: one line and an exit status.

Each layer raises its own error: daq.formats.errors.FormatError (a file that is not
what it claims), daq.store.StoreError (the run store), daq.workflows.errors.WorkflowError
(a workflow step), drivers.errors.DriverError (the instrument link), and the command
line itself :class:`UserError` (bad input, defined here). :func:`exit_code_and_message` is the one
place that turns them into the status and the line ``daq: error: ...`` that main()
(daq/cli/app.py) prints; anything else is not the user's to fix.
"""

from __future__ import annotations

import sys

from daq.workflows.errors import WorkflowError
from drivers.errors import DriverError


class UserError(Exception):
    """Something the user can fix at the command line: a bad option, a missing file, a
    step that cannot run as asked. Raised only in daq/cli/; the layers below raise
    their own errors, mapped by :func:`exit_code_and_message`.

    ``exit_code`` follows sysexits loosely: 1 for most, 2 for bad usage.
    """

    def __init__(self, message: str, exit_code: int = 1) -> None:
        super().__init__(message)
        self.exit_code = exit_code


def _loaded_class(module: str, name: str) -> type[BaseException] | None:
    """The class ``module.name`` if that module has been imported, else None.

    daq.store pulls in h5py and daq.formats numpy and pyuff: `daq --version` must not
    pay for them. An exception of a class whose module was never imported cannot
    have been raised, so looking only in sys.modules misses nothing.
    """
    found = getattr(sys.modules.get(module), name, None)
    return found if isinstance(found, type) and issubclass(found, BaseException) else None


def exit_code_and_message(exc: BaseException) -> tuple[int, str] | None:
    """(exit status, one-line message) for an error the user can fix, else None.

    Each layer's class is its own (none derives from another's), so the order of the
    checks does not matter.
    """
    format_error = _loaded_class("daq.formats.errors", "FormatError")
    store_error = _loaded_class("daq.store.errors", "StoreError")
    if format_error is not None and isinstance(exc, format_error):
        code = exc.exit_code  # type: ignore[attr-defined]
    elif store_error is not None and isinstance(exc, store_error):
        code = 1
    elif isinstance(exc, (WorkflowError, UserError)):
        code = exc.exit_code
    elif isinstance(exc, DriverError):
        code = 1
    else:
        return None
    # One line, whatever the message holds: the contract with scripts and technicians.
    return code, " ".join(str(exc).split())

"""What the command line makes of the layers' errors: one line and an exit status.

Each layer raises its own error: daq.formats.errors.FormatError (a file that is not
what it claims), daq.store.StoreError (the run store), daq.workflows.errors.WorkflowError
(a workflow step), drivers.errors.DriverError (the instrument link), and the command
line itself daq.errors.UserError (bad input). :func:`exit_code_and_message` is the one
place that turns them into the status and the line ``daq: error: ...`` that main()
(daq/cli/app.py) prints; anything else is not the user's to fix.
"""

from __future__ import annotations

import sys

from daq.errors import UserError
from daq.workflows.errors import WorkflowError
from drivers.errors import DriverError


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

    The most specific classes come first: StoreError still derives from UserError,
    and the answer must not change when it no longer does.
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

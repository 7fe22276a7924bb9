"""Errors the command line reports as one line on stderr."""


class UserError(Exception):
    """Something the user can fix: bad input, a missing file, an unreachable instrument.

    ``exit_code`` follows sysexits loosely: 1 for most, 2 for bad usage.
    """

    def __init__(self, message: str, exit_code: int = 1) -> None:
        super().__init__(message)
        self.exit_code = exit_code

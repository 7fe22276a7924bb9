"""Write docs/cli.md, the `daq` command reference, from the typer application.

    .venv/bin/python -m daq.cli.reference > docs/cli.md

Each command's section is its `--help` exactly as a terminal 80 columns wide or
wider shows it, so that the page and the program cannot tell different stories;
tests/cli/test_cli_reference.py fails when docs/cli.md is stale. typer's own
`typer ... utils docs` is not used: it drops the -h alias, cuts summaries at 45
characters and lets <placeholders> in help texts read as HTML in Markdown.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from typing import Any

import typer

from daq.cli.app import app

REGENERATE = ".venv/bin/python -m daq.cli.reference > docs/cli.md"

#: Click's help formatter uses the terminal width less 2, at most 80 - 2.
HELP_WIDTH = 78

PREAMBLE = f"""\
# `daq` command reference

> Generated from the help texts in `daq/*.py`; do not edit by hand. After changing
> a help text, regenerate with `{REGENERATE}`
> (tests/cli/test_cli_reference.py fails while this page is stale).

Every command prints `--help` (or `-h`). Errors are one line on stderr,
`daq: error: ...`, with these exit statuses:

| Status | Meaning |
|---|---|
| 0 | done |
| 1 | something you can fix: a bad file, an unreachable instrument, an instrument error |
| 2 | bad usage: an unknown option, a value out of range |
| 70 | a bug in daq; run again with `DAQ_DEBUG=1` for the traceback |
| 130 | interrupted (Ctrl-C) |

Environment: `DAQ_RESOURCE` gives `--resource` its value; `DAQ_DEBUG=1` shows the
traceback of an internal error.
"""


def _walk(command: Any, name: str, parent: typer.Context | None) -> Iterator[tuple[str, str, str]]:
    """(command path, one-line summary, full help) of ``command`` and every command under it.

    ``command`` is what typer.main.get_command gives: click's public Command and
    Group API (make_context, get_help, list_commands, get_command) is all it needs.
    """
    # resilient_parsing: no "missing argument" for the empty command line.
    ctx = command.make_context(
        name, [], parent=parent, resilient_parsing=True, terminal_width=HELP_WIDTH, max_content_width=80
    )
    with ctx:
        yield ctx.command_path, command.get_short_help_str(HELP_WIDTH), command.get_help(ctx)
        # Groups list their commands in the order they were added, as their help does.
        if hasattr(command, "list_commands"):
            for sub in command.list_commands(ctx):
                yield from _walk(command.get_command(ctx, sub), sub, ctx)


def reference() -> str:
    """The text of docs/cli.md."""
    sections = list(_walk(typer.main.get_command(app), "daq", None))
    lines = [PREAMBLE, "## Commands", ""]
    for path, summary, _ in sections[1:]:
        anchor = path.replace(" ", "-")
        lines.append(f"- [`{path}`](#{anchor}): {summary.replace('<', '&lt;')}")
    for path, _, help_text in sections:
        lines += ["", f"## {path}", "", "```text", help_text, "```"]
    return "\n".join(lines) + "\n"


def main() -> None:
    sys.stdout.write(reference())


if __name__ == "__main__":
    main()

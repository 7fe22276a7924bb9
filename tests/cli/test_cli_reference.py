"""docs/cli.md is the `daq` help, current and complete."""

import re
from pathlib import Path

from daq.cli.reference import REGENERATE, reference
from tests.cli_helpers import invoke_daq

CLI_MD = Path(__file__).resolve().parents[2] / "docs" / "cli.md"
SECTION = re.compile(r"^## (daq[a-z ]*)\n\n```text\n(.*?)\n```$", re.MULTILINE | re.DOTALL)


def _sections(text: str) -> dict[str, str]:
    return dict(SECTION.findall(text))


def test_docs_cli_md_is_current():
    assert CLI_MD.read_text(encoding="utf-8") == reference(), f"docs/cli.md is stale: run {REGENERATE}"


def test_each_section_is_what_help_prints():
    sections = _sections(CLI_MD.read_text(encoding="utf-8"))
    assert sections, "no command sections in docs/cli.md"
    for path, text in sections.items():
        result = invoke_daq(*path.split()[1:], "--help")
        assert result.returncode == 0, result.stderr
        assert result.stdout == text + "\n", path


def test_every_command_has_a_section():
    sections = _sections(CLI_MD.read_text(encoding="utf-8"))
    assert "daq" in sections
    for path, text in sections.items():
        listed = text.partition("\nCommands:\n")[2]
        for line in listed.splitlines():
            name = line.split()[0]
            assert f"{path} {name}" in sections, f"{path} {name} has no section in docs/cli.md"
    assert {"daq model", "daq sim serve", "daq query"} <= sections.keys()


def test_the_page_says_how_to_regenerate_it():
    head = CLI_MD.read_text(encoding="utf-8")[:500]
    assert REGENERATE in head
    assert REGENERATE.endswith("> docs/cli.md")

"""The documentation stands on its own and so does the repository.

1. Every relative link in README.md and docs/*.md leads to a file or directory of
   the repository (web and mail links are not followed; ``#anchors`` are ignored;
   links inside code blocks and code spans are not links).
2. No text file of the repository (tracked, or new and not ignored) refers to
   material kept outside it: the design notes, the folder they live in, the
   paper's file, or a ``../`` path that climbs out of the repository. The failure
   lists every offending ``file:line``, so that a sweep can fix them all at once.

A ``../`` inside the repository (a test feeding ``../x`` to a path validator,
resolved from its own folder) is not a reference to the outside and passes.
This file spells the forbidden strings in pieces so that it does not match itself.
"""

from __future__ import annotations

import re
import subprocess
from pathlib import Path
from urllib.parse import unquote

import pytest

ROOT = Path(__file__).resolve().parents[1]
THIS_FILE = Path(__file__).resolve().relative_to(ROOT).as_posix()

#: Strings that name material outside the repository, built so this file holds none.
FORBIDDEN = (
    "shared" + "/",
    "DESIGN" + ".md",
    "d58cf785" + "c5f08ede",  # the paper's file name
)
PARENT = "." + "./"

_FENCE = re.compile(r"^ {0,3}(`{3,}|~{3,})")
_CODE_SPAN = re.compile(r"(`+).*?\1")
_INLINE_LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*(<[^>]*>|[^)\s]+)(?:\s+[\"'(][^)]*)?\)")
_REFERENCE_DEF = re.compile(r"^ {0,3}\[[^\]]+\]:\s*(<[^>]*>|\S+)")
_HTML_LINK = re.compile(r"""(?:href|src)\s*=\s*["']([^"']+)["']""", re.IGNORECASE)
_EXTERNAL = re.compile(r"^(?:[a-z][a-z0-9+.-]*:|//)", re.IGNORECASE)
_PATH_TOKEN = re.compile(r"[\w.~/-]*\.\./[\w.~/-]*")


def _markdown_files() -> list[Path]:
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def _prose_lines(text: str) -> list[tuple[int, str]]:
    """(line number, line) outside fenced code blocks, with code spans blanked."""
    out: list[tuple[int, str]] = []
    fence: str | None = None
    for number, line in enumerate(text.splitlines(), start=1):
        match = _FENCE.match(line)
        if fence is None and match:
            fence = match.group(1)
            continue
        if fence is not None:
            stripped = line.strip()
            if stripped.startswith(fence[0] * len(fence)) and not stripped.strip(fence[0]):
                fence = None
            continue
        out.append((number, _CODE_SPAN.sub("", line)))
    return out


def _links(path: Path) -> list[tuple[int, str]]:
    found = []
    for number, line in _prose_lines(path.read_text(encoding="utf-8")):
        targets = [m.group(1) for m in _INLINE_LINK.finditer(line)]
        targets += [m.group(1) for m in _REFERENCE_DEF.finditer(line)]
        targets += [m.group(1) for m in _HTML_LINK.finditer(line)]
        found += [(number, t[1:-1] if t.startswith("<") else t) for t in targets]
    return found


def _broken_link(source: Path, target: str) -> str | None:
    """Why ``target`` (a link in ``source``) is broken, or None if it resolves."""
    if _EXTERNAL.match(target) or target.startswith("#"):
        return None
    path_part = unquote(target.split("#", 1)[0].split("?", 1)[0])
    if not path_part:
        return None
    base = ROOT if path_part.startswith("/") else source.parent
    resolved = (base / path_part.lstrip("/")).resolve()
    if not resolved.is_relative_to(ROOT):
        return "leads out of the repository"
    if not resolved.exists():
        return "no such file or directory"
    return None


def test_the_pages_exist():
    for name in ("README.md", "method.md", "instrument.md", "simulator.md", "architecture.md", "guide.md"):
        path = ROOT / name if name == "README.md" else ROOT / "docs" / name
        assert path.is_file(), f"{path.relative_to(ROOT)} is missing"


def test_every_relative_link_in_the_docs_resolves():
    broken = []
    for path in _markdown_files():
        for number, target in _links(path):
            reason = _broken_link(path, target)
            if reason:
                broken.append(f"{path.relative_to(ROOT).as_posix()}:{number}: {target} ({reason})")
    assert not broken, "broken links:\n" + "\n".join(broken)


def test_links_in_code_do_not_count_and_anchors_are_ignored():
    """The link finder itself, on a page written here."""
    page = ROOT / "docs" / "page.md"  # never written: only its folder matters
    text = (
        "See [method](method.md#reproduced-numbers), [web](https://example.org/x.md),\n"
        "`[not a link](nowhere.md)` and [ref]: guide.md\n"
        "```sh\n[inside a fence](nowhere.md)\n```\n"
        "![figure](missing.png)\n"
    )
    targets = []
    for _, line in _prose_lines(text):
        targets += [m.group(1) for m in _INLINE_LINK.finditer(line)]
        targets += [m.group(1) for m in _REFERENCE_DEF.finditer(line)]
    assert targets == ["method.md#reproduced-numbers", "https://example.org/x.md", "missing.png"]
    assert _broken_link(page, "https://example.org/x.md") is None
    assert _broken_link(page, "#anchor") is None
    assert _broken_link(page, "missing.png") == "no such file or directory"
    assert _broken_link(page, PARENT * 3 + "etc") == "leads out of the repository"


def _repository_files() -> list[str]:
    try:
        listing = subprocess.run(
            ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
            cwd=ROOT,
            capture_output=True,
            check=True,
        ).stdout
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout: cannot list the repository's files")
    return sorted({name for name in listing.decode("utf-8", "replace").split("\0") if name})


def _text(path: Path) -> str | None:
    """The file's text, or None for binary files (a NUL byte, or not UTF-8)."""
    try:
        data = path.read_bytes()
    except OSError:
        return None  # listed but deleted from the work tree
    if b"\0" in data[:8192]:
        return None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return None


def _outside_references(name: str, text: str) -> list[str]:
    folder = (ROOT / name).parent
    found = []
    for number, line in enumerate(text.splitlines(), start=1):
        hits = [s for s in FORBIDDEN if s in line]
        for token in _PATH_TOKEN.findall(line):
            if not (folder / token).resolve().is_relative_to(ROOT):
                hits.append(token)
        if hits:
            found.append(f"{name}:{number}: {', '.join(hits)}: {line.strip()[:120]}")
    return found


def test_nothing_refers_to_material_outside_the_repository():
    offending = []
    for name in _repository_files():
        if name == THIS_FILE:
            continue
        text = _text(ROOT / name)
        if text is not None:
            offending += _outside_references(name, text)
    assert not offending, (
        f"{len(offending)} line(s) refer to material outside the repository; say it in the "
        "repository's own words (docs/) and cite the source by title instead:\n" + "\n".join(offending)
    )


def test_the_outside_reference_finder():
    """The finder itself: the forbidden names, and ``../`` only when it climbs out."""
    assert _outside_references("README.md", "see " + FORBIDDEN[1]) != []
    assert _outside_references("docs/x.md", "the notes in " + FORBIDDEN[0] + "seed") != []
    assert _outside_references("README.md", "[notes](" + PARENT + "notes.md)") != []
    assert _outside_references("docs/x.md", "[up](" + PARENT + "README.md)") == []
    assert _outside_references("tests/store/t.py", '"' + PARENT + 'x"') == []
    assert _outside_references("tests/t.py", "a shared lock, our design notes") == []

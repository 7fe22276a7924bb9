"""Typing a reply's text by the kind a command table gives it, for every dialect."""

from __future__ import annotations

import math
import re


def typed_value(
    text: str, kind: str, choices: tuple[str, ...] = (), what: str = "the query", whole_integers: bool = False
) -> float | int | bool | str:
    """``text`` (stripped) as ``kind`` says: "text" as is, "choice" one of ``choices``,
    "flag" 0/1 -> bool, "number" a finite float (SI), "integer" an int.
    ``whole_integers``: an integer must be written as one (SCPI's NR1), not as 5.0.
    ValueError with the reason when the text does not fit."""
    if kind == "text":
        return text
    if kind == "choice":
        if text not in choices:
            raise ValueError(f"expected one of {', '.join(choices)}")
        return text
    if kind == "flag":
        if text not in ("0", "1"):
            raise ValueError("expected 0 or 1")
        return text == "1"
    try:
        x = float(text)
    except ValueError:
        raise ValueError("expected a number") from None
    if not math.isfinite(x):
        raise ValueError("expected a finite number")
    if kind == "integer":
        if x != int(x) or (whole_integers and not re.fullmatch(r"[+-]?\d+", text)):
            raise ValueError("expected an integer (NR1)" if whole_integers else "expected an integer")
        return int(x)
    if kind == "number":
        return x
    raise ValueError(f"{what} does not answer one line")

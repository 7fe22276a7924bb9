"""Faults on demand, armed per connection, deterministic.

A fault spec is ``name[,key=value...]``, e.g. ``truncate``, ``slow,delay=0.2``,
``garbage,count=2,after=1``. Every fault fires on its eligible events, skipping
the first ``after`` of them, ``count`` times (``count=always`` for ever).

| name     | eligible event     | what happens                                                  |
|----------|--------------------|---------------------------------------------------------------|
| slow     | every reply        | the reply is held back ``delay`` seconds (default 0.5; always)|
| no_hit   | STRT (SCPI: INIT)  | the hammer never strikes: the analyzer waits for a trigger    |
| truncate | a binary block     | only ``keep`` of it is sent (default 0.5), the rest never     |
| garbage  | every reply        | ``nbytes`` random bytes (default 8) are sent before the reply |
| drop     | a binary block     | ``keep`` of it is sent, then the connection is closed         |
| error    | (at once)          | the instrument enters a hardware-fault state until (*)RST     |
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass, field

FAULTS = ("slow", "no_hit", "truncate", "garbage", "drop", "error")
MAX_GARBAGE_BYTES = 65536
_DEFAULT_COUNT = {"slow": math.inf}
_PARAMS = {
    "slow": {"delay": 0.5},
    "no_hit": {},
    "truncate": {"keep": 0.5},
    "garbage": {"nbytes": 8.0, "seed": 0.0},
    "drop": {"keep": 0.5},
    "error": {},
}


@dataclass
class Fault:
    name: str
    count: float = 1.0
    after: int = 0
    params: dict[str, float] = field(default_factory=dict)
    seen: int = 0
    fired: int = 0

    def fires(self) -> bool:
        """Called on each eligible event: whether the fault acts on this one."""
        self.seen += 1
        if self.seen <= self.after or self.fired >= self.count:
            return False
        self.fired += 1
        return True

    @property
    def exhausted(self) -> bool:
        return self.fired >= self.count

    def describe(self) -> str:
        count = "always" if math.isinf(self.count) else str(int(self.count))
        extra = "".join(f",{k}={v:g}" for k, v in self.params.items())
        return f"{self.name},count={count},after={self.after}{extra}"


def parse_fault(spec: str) -> Fault:
    """``name[,key=value...]`` -> Fault; ValueError with a clear message otherwise."""
    name, *pairs = [p.strip() for p in spec.strip().split(",")]
    name = name.lower()
    if name not in FAULTS:
        raise ValueError(f"unknown fault {name!r}; known: {', '.join(FAULTS)}")
    fault = Fault(name, count=_DEFAULT_COUNT.get(name, 1.0), params=dict(_PARAMS[name]))
    for pair in pairs:
        key, sep, value = pair.partition("=")
        key = key.strip().lower()
        if not sep:
            raise ValueError(f"fault option {pair!r} is not key=value")
        try:
            if key == "count":
                fault.count = math.inf if value.strip().lower() == "always" else float(int(value))
            elif key == "after":
                fault.after = int(value)
            elif key in fault.params:
                number = float(value)
                if not math.isfinite(number):
                    raise ValueError("not finite")
                fault.params[key] = number
            else:
                raise ValueError(
                    f"fault {name} has no option {key!r}; options: count, after"
                    + "".join(f", {k}" for k in fault.params)
                )
        except ValueError as exc:
            if "has no option" in str(exc):
                raise
            raise ValueError(f"fault option {pair!r}: not a number") from None
        if fault.count < 0 or fault.after < 0:
            raise ValueError("fault count and after must not be negative")
    keep = fault.params.get("keep")
    if keep is not None and not 0.0 <= keep < 1.0:
        raise ValueError("keep must be at least 0 and below 1")
    if fault.params.get("delay", 0.0) < 0:
        raise ValueError("delay must not be negative")
    if not 0 <= fault.params.get("nbytes", 0.0) <= MAX_GARBAGE_BYTES:
        raise ValueError(f"nbytes must be 0..{MAX_GARBAGE_BYTES}")
    return fault


def garbage_bytes(fault: Fault) -> bytes:
    """Deterministic junk: high-bit and control bytes that no reply contains."""
    rng = random.Random(int(fault.params["seed"]) * 1000 + fault.fired)
    return bytes(rng.choice(range(0x80, 0x100)) for _ in range(int(fault.params["nbytes"])))

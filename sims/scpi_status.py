"""SCPI status reporting of the simulated 35670A: the error queue, the standard event
register, the status byte and the OPERation / QUEStionable registers
(docs/instrument-scpi.md, "Status").

Registers: a condition follows the measurement; its event register latches
positive transitions (as after STAT:PRES: every rising bit, no falling one) and is
cleared by reading it or *CLS; the enable registers choose what reaches the
status byte. Time is lazy (sims/measurement.py): the states the measurement went
through between two looks are latched too, so a hit recorded entirely between
two commands still leaves its events.
"""

from __future__ import annotations

from collections import deque

from sims.measurement import Measurement

#: SCPI's standard error messages for the codes the simulator queues.
MESSAGES = {
    -102: "Syntax error",
    -104: "Data type error",
    -108: "Parameter not allowed",
    -109: "Missing parameter",
    -113: "Undefined header",
    -114: "Header suffix out of range",
    -131: "Invalid suffix",
    -221: "Settings conflict",
    -222: "Data out of range",
    -224: "Illegal parameter value",
    -230: "Data corrupt or stale",
    -240: "Hardware error",
    -350: "Queue overflow",
    -363: "Input buffer overrun",
}
#: The mnemonic dialect's codes (docs/instrument.md), used by the front ends and
#: SIM: controls, as SCPI codes.
FROM_MNEMONIC_CODE = {1: -113, 2: -222, 3: -224, 4: -131, 5: -230, 6: -221, 7: -240, 8: -363}
MAX_ERRORS = 32

# Operation condition bits: 4 and 5 are SCPI's; 8 and 9 the project's.
OPER_MEASURING = 16
OPER_WAITING_FOR_TRIGGER = 32
OPER_DONE = 256
OPER_HIT_PENDING = 512
# Questionable: bit 0 summarises the voltage (overload) register.
QUES_VOLTAGE = 1
# Status byte (IEEE 488.2 / SCPI).
STB_ERROR_QUEUE = 4
STB_QUESTIONABLE = 8
STB_EVENT_SUMMARY = 32
STB_MASTER_SUMMARY = 64
STB_OPERATION = 128
# Standard event register.
ESR_OPC = 1
ESR_BY_CLASS = {-4: 4, -3: 8, -2: 16, -1: 32}  # query, device, execution, command errors


def _oper_bits(state: str) -> int:
    return {
        "waiting": OPER_MEASURING | OPER_WAITING_FOR_TRIGGER,
        "measuring": OPER_MEASURING,
        "pending": OPER_MEASURING | OPER_HIT_PENDING,
        "done": OPER_DONE,
    }.get(state, 0)


class ScpiStatus:
    def __init__(self) -> None:
        self.errors: deque[tuple[int, str]] = deque()
        self.esr = 0
        self.ese = 0
        self.sre = 0
        self.oper_event = self.oper_enable = 0
        self.ques_event = self.ques_enable = 0
        self.volt_event = 0
        self.opc_armed = False
        self._oper_seen = 0
        self._volt_seen = 0

    # ------------------------------------------------------------- errors
    def push(self, code: int, detail: str) -> None:
        """Queue SCPI error ``code``; a full queue's last entry becomes -350."""
        self.esr |= ESR_BY_CLASS.get(max(-((-code) // 100), -4), 0)
        if len(self.errors) >= MAX_ERRORS:
            self.errors.pop()
            code, detail = -350, ""
        message = MESSAGES[code] + (f"; {detail}" if detail else "")
        self.errors.append((code, message.replace('"', "'")))

    def pop(self) -> str:
        """SYST:ERR?'s reply: ``+0,"No error"`` or ``-113,"Undefined header; ..."``."""
        if not self.errors:
            return '+0,"No error"'
        code, message = self.errors.popleft()
        return f'{code:+d},"{message}"'

    # ------------------------------------------------------------ registers
    @staticmethod
    def oper_condition(m: Measurement) -> int:
        return _oper_bits(m.state)

    @staticmethod
    def volt_condition(m: Measurement) -> int:
        over = m.overload
        return (1 if over[0] else 0) | (2 if over[1] else 0)

    def ques_condition(self, m: Measurement) -> int:
        return QUES_VOLTAGE if self.volt_condition(m) else 0

    def look(self, m: Measurement, pending: bool) -> None:
        """Latch what happened since the last look; ``pending``: a measurement is not
        finished (what *OPC waits for)."""
        passed = 0
        for state in m.entered:
            passed |= _oper_bits(state)
        m.entered.clear()
        now = self.oper_condition(m)
        self.oper_event |= (passed | now) & ~self._oper_seen
        self._oper_seen = now
        volt = self.volt_condition(m)
        risen = volt & ~self._volt_seen
        self.volt_event |= risen
        if risen:
            self.ques_event |= QUES_VOLTAGE
        self._volt_seen = volt
        if self.opc_armed and not pending:
            self.esr |= ESR_OPC
            self.opc_armed = False

    def clear(self) -> None:
        """*CLS."""
        self.errors.clear()
        self.esr = 0
        self.oper_event = self.ques_event = self.volt_event = 0
        self.opc_armed = False

    def preset(self) -> None:
        """STAT:PRES."""
        self.oper_enable = self.ques_enable = 0

    def stb(self) -> int:
        """The status byte (MAV is 0: the reply to *STB? is what is being read)."""
        bits = STB_ERROR_QUEUE if self.errors else 0
        bits |= STB_QUESTIONABLE if self.ques_event & self.ques_enable else 0
        bits |= STB_EVENT_SUMMARY if self.esr & self.ese else 0
        bits |= STB_OPERATION if self.oper_event & self.oper_enable else 0
        if bits & self.sre & ~STB_MASTER_SUMMARY:
            bits |= STB_MASTER_SUMMARY
        return bits

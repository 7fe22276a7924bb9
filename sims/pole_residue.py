"""Linear systems as sums of first-order poles, and their exact response to half-sine pulses.

A system G(s) = sum_i r_i / (s - p_i) + D maps an input u(t) to

    y(t) = sum_i r_i (e^(p_i t) * u)(t) + D u(t).

For half-sine pulses u(t) = A sin(pi (t - t0) / w) on [t0, t0 + w] the convolution
has a closed form, so the simulator samples the *continuous* response of the
beam, its sensors and the analyzer's anti-alias filter at any instants, with no
discretisation error: the hold and step-size questions of a numerical
simulation never arise.

Series connections combine by partial fractions (poles of the two parts must be
distinct, which a structure and an electronic filter always are in practice).

A system may also have poles in the right half-plane: read as a stable two-sided
system (the region of convergence holds the imaginary axis), those terms are
anti-causal, r / (s - p) <-> -r e^(p t) for t < 0. That is how a zero-phase
filter H(s) H(-s) is written: it answers before its input as much as after, as a
linear-phase digital filter does once its bulk delay is removed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class HalfSinePulses:
    """K half-sine force pulses: start times (s), widths (s) and peak values (input units).

    Each array has shape (K,). An empty set of pulses is allowed.
    """

    start_s: np.ndarray
    width_s: np.ndarray
    peak: np.ndarray

    def __post_init__(self) -> None:
        for name in ("start_s", "width_s", "peak"):
            object.__setattr__(self, name, np.atleast_1d(np.asarray(getattr(self, name), dtype=float)))
        if not (self.start_s.shape == self.width_s.shape == self.peak.shape) or self.start_s.ndim != 1:
            raise ValueError("pulse start, width and peak must be 1-D arrays of one length")
        if np.any(self.width_s <= 0):
            raise ValueError("pulse widths must be positive")

    def value(self, times_s: np.ndarray) -> np.ndarray:
        """The input itself at the given instants, shape of ``times_s``."""
        t = np.asarray(times_s, dtype=float)[..., None]
        s = t - self.start_s
        inside = (s >= 0) & (s <= self.width_s)
        return np.where(inside, self.peak * np.sin(np.pi * s / self.width_s), 0.0).sum(axis=-1)


@dataclass(frozen=True)
class PoleResidueSystem:
    """G(s) = sum_i residues_i / (s - poles_i) + direct.

    poles, residues : (W,) complex, rad/s and output units per input unit per second.
    direct : feed-through, output units per input unit.
    A real system has its poles in conjugate pairs with conjugate residues; its
    response is then real to round-off and ``respond`` returns the real part.
    """

    poles: np.ndarray
    residues: np.ndarray
    direct: float = 0.0

    @classmethod
    def from_state_space(cls, a: np.ndarray, b: np.ndarray, c: np.ndarray, d: float) -> PoleResidueSystem:
        """From x' = A x + B u, y = C x + D u with a diagonalizable A (2-D, 1-D, 1-D, scalar)."""
        lam, vec = np.linalg.eig(a)
        g = np.linalg.solve(vec, b.astype(complex))
        return cls(lam, (c @ vec) * g, float(d))

    @classmethod
    def from_zpk(cls, zeros: np.ndarray, poles: np.ndarray, gain: float) -> PoleResidueSystem:
        """From zeros, poles and gain of a proper rational function with simple poles."""
        zeros = np.asarray(zeros, dtype=complex)
        poles = np.asarray(poles, dtype=complex)
        if zeros.size > poles.size:
            raise ValueError("improper transfer function")
        residues = np.array(
            [gain * np.prod(p - zeros) / np.prod(p - np.delete(poles, i)) for i, p in enumerate(poles)]
        )
        direct = float(np.real(gain)) if zeros.size == poles.size else 0.0
        return cls(poles, residues, direct)

    def evaluate(self, s: np.ndarray) -> np.ndarray:
        """G(s) at complex frequencies s (any shape)."""
        s = np.asarray(s, dtype=complex)
        return (self.residues / (s[..., None] - self.poles)).sum(axis=-1) + self.direct

    def then(self, after: PoleResidueSystem) -> PoleResidueSystem:
        """The series connection: this system followed by ``after`` (G = G_after G_self)."""
        res_self = self.residues * after.evaluate(self.poles)
        res_after = after.residues * self.evaluate(after.poles)
        return PoleResidueSystem(
            np.concatenate([self.poles, after.poles]),
            np.concatenate([res_self, res_after]),
            self.direct * after.direct,
        )

    def moved(self, shift_hz: float) -> PoleResidueSystem:
        """G(s - j 2 pi shift_hz): the response moved up the frequency axis (complex
        coefficients). A low-pass moved by f_c and then mixed down by f_c is the
        low-pass again: how a zoom band is selected."""
        return PoleResidueSystem(self.poles + 2j * np.pi * shift_hz, self.residues, self.direct)

    def scaled(self, factor: float) -> PoleResidueSystem:
        """factor * G(s)."""
        return PoleResidueSystem(self.poles, self.residues * factor, self.direct * factor)

    def respond(self, pulses: HalfSinePulses, times_s: np.ndarray, shift_hz: float = 0.0) -> np.ndarray:
        """Exact output at ``times_s`` (any shape, s) to the pulses.

        Poles in the left half-plane act causally (from rest before the pulses),
        poles in the right half-plane anti-causally (at rest after the pulses); see
        the module's docstring. Returns real values of the shape of ``times_s``; with
        ``shift_hz`` = f_c, the complex output mixed down by f_c.
        """
        t = np.asarray(times_s, dtype=float)
        ahead = self.poles.real > 0
        causal = PoleResidueSystem(self.poles[~ahead], self.residues[~ahead], self.direct)
        out = causal._respond_causal(pulses, t, shift_hz)
        if ahead.any():
            # Time reversal turns the anti-causal part into a causal one: with
            # u'(t) = u(-t), y(t) = (g' * u')(-t) where g' has poles -p and residues
            # -r; the reversed half-sine pulses are half-sine pulses again, and the
            # mixing e^(-j w_c t) is the reversed system's mixing by -f_c at -t.
            mirrored = PoleResidueSystem(-self.poles[ahead], -self.residues[ahead], 0.0)
            reversed_pulses = HalfSinePulses(-(pulses.start_s + pulses.width_s), pulses.width_s, pulses.peak)
            out = out + mirrored._respond_causal(reversed_pulses, -t, -shift_hz)
        return out

    def _respond_causal(self, pulses: HalfSinePulses, times_s: np.ndarray, shift_hz: float) -> np.ndarray:
        """``respond`` for a system whose poles all act causally.

        With ``shift_hz`` = f_c the output is mixed down by f_c, y(t) e^(-j 2 pi f_c t),
        as a zoom analyzer's digital local oscillator does (filter it afterwards).

        Each pulse is A sin(a s) = sum_m c_m e^(k_m s) on 0 <= s <= w (s = t - t0,
        a = pi / w), so each pole's state is a sum of exponentials in closed form:
        z(s) = sum_m c_m (e^(k_m s_c + q (s - s_c)) - e^(q s)) / (k_m - q), with
        s_c = min(s, w) and q the pole moved by the mixing.
        """
        t = np.asarray(times_s, dtype=float)
        out = np.zeros(t.shape, dtype=complex)
        w_c = 2 * np.pi * shift_hz
        q = self.poles - 1j * w_c
        for start, width, peak in zip(pulses.start_s, pulses.width_s, pulses.peak, strict=True):
            a = np.pi / width
            s = np.maximum(t - start, 0.0)[..., None]  # time since the pulse began, (..., 1)
            sc = np.minimum(s, width)
            # sin(a s) e^(-j w_c (t0 + s)) = sum over +-: +-e^(-j w_c t0) / 2j * e^((+-j a - j w_c) s)
            coef = peak * np.exp(-1j * w_c * start) / 2j
            state = np.zeros(np.broadcast_shapes(s.shape, q.shape), dtype=complex)
            for sign in (1.0, -1.0):
                kappa = sign * 1j * a - 1j * w_c
                denom = kappa - q  # = +-j a - p: independent of the mixing
                # A pole exactly at the pulse's own frequency (undamped) would divide
                # by zero; nudge it, the response is continuous in p.
                denom = np.where(np.abs(denom) < 1e-9 * a, 1e-9 * a, denom)
                with np.errstate(over="ignore", invalid="ignore"):
                    term = (np.exp(kappa * sc + q * (s - sc)) - np.exp(q * s)) / denom
                state += sign * coef * term
            state = np.where(s > 0, state, 0.0)
            out += (state * self.residues).sum(axis=-1)
        direct = self.direct * pulses.value(t)
        if shift_hz == 0.0:
            return out.real + direct
        return out + direct * np.exp(-1j * w_c * t)

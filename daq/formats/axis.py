"""Is a printed time column regular? The rule every reader of time records shares.

A column is regular when a straight line t_k = start + k * step passes within the
tolerance of every value, where a value's tolerance is the larger of

- the precision it was printed with: half a unit of its last printed digit, and
- 1 % of the step.

So a 51.2 kHz record printed with 7 significant digits (1.953125e-05, ...,
0.9999805) is regular although its printed steps differ by several percent near 1 s,
while a dropped sample (one step twice as long) or a jump is refused. The run stores the
fitted step, not any printed one.

Trailing zeros: %g drops them ("0.5" for 0.5000000), so a value's own last digit can
claim less precision than the column has. The column's precision is taken from all its
values: the most decimals any value shows (fixed-point writers, %f) or the most
significant digits (%e, %g), whichever claims less; a value's tolerance is never looser
than its own last digit says. Except where a notation keeps its trailing zeros: a value
printed with a zero as its last decimal after another digit ("2.50E-04", not "1.0")
shows that its writer pads, so the values printed in that notation (with an exponent,
or without) hold their own last digit, but for zeros, which are exact. Excel-style
exports print 3 significant digits with an exponent below 0.1 s and every digit above
("7.08E-02", then "0.10025"): the column's 5 digits are no precision of "7.08E-02".
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

STEP_FRACTION = 0.01  # a value may sit 1 % of the step off the line, whatever its precision
# Printed so coarsely that half a unit is more than a quarter of the step (integer
# milliseconds at 1 kHz), a column cannot show a dropped sample within its precision:
# its values then count with a quarter of the step, so a dropped sample is still refused.
COARSEST_FRACTION = 0.25
_NUMBER = re.compile(r"\s*[-+]?([0-9]*)(?:[.,]([0-9]*))?(?:[eE]([-+]?[0-9]+))?\s*")


@dataclass(frozen=True)
class AxisFit:
    """A regular axis: first value and step (fitted), or where it is not regular.

    start, step: the fitted line (step > 0) when ``bad`` is None.
    bad: index of the first value that breaks the rule (the later one of an odd step).
    tolerance: the largest tolerance used (s, or the column's unit).
    """

    start: float
    step: float
    bad: int | None
    tolerance: float


def printed_half_units(texts: list[str]) -> np.ndarray:
    """Half a unit of the last printed digit of each value, with the column's precision.

    texts: the values as printed (decimal point or decimal comma, optional exponent).
    Returns (n,) float64 >= 0; 0 for a text it cannot read (never looser than needed).
    """
    n = len(texts)
    quantum = np.zeros(n, dtype=np.int64)  # exponent of the last printed digit
    sig = np.zeros(n, dtype=np.int64)  # significant digits printed
    lead = np.zeros(n, dtype=np.int64)  # exponent of the first non-zero digit
    zero = np.zeros(n, dtype=bool)
    known = np.zeros(n, dtype=bool)
    exponent = np.zeros(n, dtype=bool)  # printed with an exponent
    padded = np.zeros(n, dtype=bool)  # a zero as the last decimal: the writer keeps them
    for i, text in enumerate(texts):
        match = _NUMBER.fullmatch(text)
        if match is None or not (match.group(1) or match.group(2)):
            continue
        whole, frac, exp = match.group(1), match.group(2) or "", int(match.group(3) or 0)
        if abs(exp) > 400:
            continue
        digits = whole + frac
        quantum[i] = exp - len(frac)
        stripped = digits.lstrip("0")
        sig[i] = len(stripped)
        zero[i] = not stripped
        lead[i] = exp + len(whole) - 1 - (len(digits) - len(stripped))
        known[i] = True
        exponent[i] = match.group(3) is not None
        # "2.50E-04", "0.10": a zero kept after a digit; not "1.0" or "0.0", which repr
        # and str print for any whole float however precise the column.
        padded[i] = frac.endswith("0") and bool(frac.rstrip("0"))
    out = np.zeros(n, dtype=np.float64)
    if not known.any():
        return out
    finest_quantum = int(quantum[known].min())  # most decimals shown: fixed-point writers
    most_sig = int(sig[known].max())  # most significant digits: %e / %g writers
    fixed = _half_unit(np.array([finest_quantum]))[0]
    relative = _half_unit(lead - most_sig + 1)
    model = np.where(zero, fixed, np.maximum(fixed, relative))
    literal = _half_unit(quantum)
    for notation in (exponent, ~exponent):
        if np.any(padded & known & notation):
            # Not a zero: "0.00E+00" is 0 s exactly, not 0 +- 0.005 s.
            model = np.where(notation & ~zero, literal, model)
    out[known] = np.minimum(literal, model)[known]
    return out


def _half_unit(exponents: np.ndarray) -> np.ndarray:
    """0.5 x 10**k for each integer k of ``exponents`` (n,), correctly rounded: the same k
    gives the same float whichever way it was reached (``10.0 ** -5`` and numpy's power of
    -5.0 differ in the last bit, and a zero's half unit then came out above its
    neighbour's)."""
    k = np.clip(np.asarray(exponents, dtype=np.int64), -400, 400)
    powers, where = np.unique(k, return_inverse=True)
    return np.array([float(f"5e{int(p) - 1}") for p in powers], dtype=np.float64)[where.reshape(k.shape)]


def fit_regular(values: np.ndarray, half_units: np.ndarray | None = None) -> AxisFit:
    """Fit a straight line to ``values`` (n >= 2, strictly increasing) within the rule.

    half_units: (n,) the printed precision of each value (printed_half_units), or None
        for values that were not printed (binary doubles): 1 % of the step then.
    """
    t = np.asarray(values, dtype=np.float64)
    n = t.size
    d = np.diff(t)
    typical = float(np.median(d))
    tol = _tolerances(t, half_units)
    k = np.arange(n, dtype=np.float64)
    # Least squares first (the usual case passes here), around the first value so that
    # a record far from t = 0 keeps its precision, each value weighed by its printed
    # precision: a spreadsheet's times printed '9.93E-02' (half a unit 20 % of the step)
    # up to 0.1 s and '0.10025' after pulled an unweighted fit to 3999.9929 Hz for 4000
    # Hz, and every mode 3 of its ± away (a new user's trial).
    rel = t - t[0]
    if half_units is None:
        w = np.ones(n)
    else:
        # By the printed half units themselves, not the tolerances (floored at 1 % of the
        # step, which would weigh '9.77E-04' as much as '0.0107421875'); scaled, so that a
        # precision near 1e-300 does not overflow.
        precision = np.maximum(np.asarray(half_units, dtype=np.float64), 1e-6 * abs(typical))
        w = 1.0 / np.square(precision / float(precision.max()))
    k_mean, rel_mean = float(np.dot(w, k) / w.sum()), float(np.dot(w, rel) / w.sum())
    kc = k - k_mean
    step = float(np.dot(w * kc, rel - rel_mean) / np.dot(w * kc, kc))
    start = float(t[0] + rel_mean - step * k_mean)
    resid = t - (start + step * k)
    if np.all(np.abs(resid) <= tol) and step > 0:
        return AxisFit(_first(t, start, tol), step, None, float(tol.max()))
    found = _band_line(rel, tol, k, prefer=step)
    if found is not None and found[1] > 0:
        return AxisFit(_first(t, t[0] + found[0], tol), found[1], None, float(tol.max()))
    # Not regular: point at the oddest step (a dropped sample, a jump) when one stands out
    # beyond what the values' tolerances allow, else at the first value off the line.
    deviation = np.abs(d - typical)
    odd = int(np.argmax(deviation))
    off = np.flatnonzero(np.abs(resid) > tol)
    bad = odd + 1 if deviation[odd] > tol[odd] + tol[odd + 1] or not off.size else int(off[0])
    return AxisFit(start, step, bad, float(tol.max()))


def step_fits(values: np.ndarray, half_units: np.ndarray | None, step: float) -> bool:
    """Whether a line of slope ``step`` (s) passes within every value's tolerance (the
    rule of fit_regular) at some start: a stated sample rate the printed times allow."""
    t = np.asarray(values, dtype=np.float64)
    tol = _tolerances(t, half_units)
    resid = (t - t[0]) - step * np.arange(t.size, dtype=np.float64)
    return float(np.max(resid - tol)) <= float(np.min(resid + tol))


def whole_rate(step: float, half_unit: float) -> int | None:
    """The one whole number of hertz among the rates a printed step allows, or None.

    step: the step as read (s, > 0); half_unit: half a unit of its last printed digit (s).
    The true step lies within step +- half_unit, so the rate within 1/(step + half_unit)
    to 1/(step - half_unit). A rate of exactly 1/step that is already whole, no whole rate
    in that range, or more than one, gives None: there is nothing to decide.
    """
    if not (step > 0 and 0 <= half_unit < step):
        return None
    low, high = 1.0 / (step + half_unit), 1.0 / (step - half_unit)
    first, last = math.ceil(low), math.floor(high)
    if first != last or first <= 0 or first == 1.0 / step:
        return None
    return int(first)


#: Sample rates acquisition hardware runs at (Hz): binary multiples (dynamic signal
#: analyzers, NI DSA cards: 2048, 25600, 51200...), round decimal ones, and audio rates.
COMMON_RATES_HZ = tuple(
    sorted(
        {float(2**k) for k in range(6, 21)}
        | {
            m * 10.0**k
            for m in (1, 1.024, 1.28, 1.6, 2, 2.048, 2.5, 2.56, 3.2, 4, 4.096, 5, 5.12, 6.4, 8, 8.192)
            for k in range(2, 6)
        }
        | {8000.0, 11025.0, 16000.0, 22050.0, 32000.0, 44100.0, 48000.0, 96000.0, 192000.0}
    )
)


def common_rate(step: float, half_unit: float) -> float | None:
    """The one rate of COMMON_RATES_HZ that a printed step allows, or None (none, or more
    than one). step, half_unit: as for whole_rate."""
    if not (step > 0 and 0 <= half_unit < step):
        return None
    low, high = 1.0 / (step + half_unit), 1.0 / (step - half_unit)
    # 0.000313 allows 3200 Hz exactly at its edge (1/0.0003125): rounding must not drop it.
    slack = 1e-9 * high
    inside = [rate for rate in COMMON_RATES_HZ if low - slack <= rate <= high + slack]
    return inside[0] if len(inside) == 1 else None


def _tolerances(t: np.ndarray, half_units: np.ndarray | None) -> np.ndarray:
    """Each value's tolerance (see the module's docstring), in the values' unit."""
    typical = float(np.median(np.diff(t)))
    h = np.zeros(t.size) if half_units is None else np.asarray(half_units, dtype=np.float64)
    tol = np.maximum(np.minimum(h, COARSEST_FRACTION * typical), STEP_FRACTION * typical)
    # A value exactly half a unit off (0.0003125 printed 0.000313) must pass despite the
    # rounding of the text to binary and of the arithmetic here: a few ulps of slack.
    return tol * (1.0 + 1e-9) + 8.0 * np.finfo(np.float64).eps * np.abs(t)


def _first(t: np.ndarray, fitted: float, tol: np.ndarray) -> float:
    """The start to store: the first value as printed (a record starting at 0 s or at the
    exporter's exact pre-trigger time keeps it), which is within its tolerance of the line."""
    return float(t[0]) if abs(float(t[0]) - fitted) <= tol[0] else float(fitted)


def _band_line(
    t: np.ndarray, tol: np.ndarray, k: np.ndarray, prefer: float | None = None
) -> tuple[float, float] | None:
    """(intercept, slope) of a line within t +- tol at every k, or None if there is none;
    of the slopes that allow one, the nearest to ``prefer`` where given (the weighted fit's,
    which a value exactly half a unit off the line can miss by a rounding: '3.12E-02' for
    0.03125 s).

    The gap g(b) = max(lo - b k) - min(hi - b k) is convex in the slope b, and a line
    exists exactly when its minimum is <= 0: golden-section search for it, then bisection
    from there towards ``prefer`` for the edge of the slopes that allow one.
    """
    lo, hi = t - tol, t + tol
    last = k[-1]
    left, right = (lo[-1] - hi[0]) / last, (hi[-1] - lo[0]) / last
    if not (math.isfinite(left) and math.isfinite(right)) or right < left:
        return None

    def gap(b: float) -> float:
        return float(np.max(lo - b * k) - np.min(hi - b * k))

    ratio = (math.sqrt(5.0) - 1.0) / 2.0
    a, b = left, right
    c, e = b - ratio * (b - a), a + ratio * (b - a)
    gc, ge = gap(c), gap(e)
    for _ in range(200):
        if gc <= 0 or ge <= 0 or b - a <= 1e-15 * max(abs(a), abs(b)):
            break
        if gc < ge:
            b, e, ge = e, c, gc
            c = b - ratio * (b - a)
            gc = gap(c)
        else:
            a, c, gc = c, e, ge
            e = a + ratio * (b - a)
            ge = gap(e)
    slope = c if gc <= ge else e
    if min(gc, ge) > 0:
        return None
    if prefer is not None and math.isfinite(prefer):
        if gap(prefer) <= 0:
            slope = prefer
        else:
            inside, outside = slope, prefer  # the feasible slopes are an interval: g is convex
            for _ in range(200):
                middle = (inside + outside) / 2.0
                if middle in (inside, outside):
                    break
                inside, outside = (middle, outside) if gap(middle) <= 0 else (inside, middle)
            slope = inside
    intercept = (np.max(lo - slope * k) + np.min(hi - slope * k)) / 2.0
    return float(intercept), float(slope)

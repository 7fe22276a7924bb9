"""Stability diagram and automatic selection of physical modes.

Pairing rule (the point of this module): a pole of order n is compared with ONE pole
of order n-1, its partner, found by a one-to-one assignment (Hungarian algorithm,
scipy.optimize.linear_sum_assignment) minimising the relative frequency distance; each
pole of order n-1 serves at most one pole of order n. Frequency, damping and modal
vector must all agree with that same partner. sdypy-EMA instead counts a pole stable
when its frequency matches any earlier pole and its damping matches any (possibly
other) earlier pole, which lets two neighbouring modes vouch for each other.

Status codes per pole:
  "new"       no partner within the frequency tolerance;
  "frequency" frequency agrees with the partner, damping does not;
  "damping"   frequency and damping agree, the modal vector does not;
  "stable"    frequency, damping and modal vector agree.

Tolerances that scale (``line_hz``, the line spacing, > 0): a damping ratio is read
from the half-power width 2 zeta f, so on a line spacing df it is known to about a
fraction of a line, not to a fixed percentage: a 0.03 % mode at 3 kHz on 1 Hz lines
spans two lines and its estimate wanders by 20 % from one order to the next while its
frequency holds to 0.01 %. The damping test is therefore
|zeta_n - zeta_{n-1}| <= max(damping_tol zeta_{n-1}, LINE_FRACTION df / f), and the
residue test, whose magnitude follows the damping (A ~ 2 zeta w |H_peak|), allows the
same relative change. With line_hz = 0 the tolerances are the fixed percentages.
Overlapping modes (a pole of order n-1 with another within OVERLAP times their summed
half-power half-widths, zeta f) trade damping between them from one order to the next:
a least-squares fit of two overlapping peaks is ill-conditioned in how it shares their
widths (on lvm-2ch m1, 160.4 Hz at 0.4 % and 163.0 Hz at 0.8 % swap 5-10 % at the top
orders, and the 163 Hz chain was found or not as a zone boundary moved by one line).
Their damping tolerance is OVERLAP_WIDENING times wider.

Modal vector agreement: ||A_n - A_{n-1}|| / ||A_{n-1}|| <= vector_tol, with A the
(n_frf,) complex residues of the pole (from the LSCF numerators). For one FRF this is
the relative change of the complex modal constant; for several it also checks the
shape (a stricter test than MAC, which ignores scale). Default 10 %: the residues of
15-20 % damped modes under 1 % noise change by 2-6 % from one order to the next, while
those of noise and numerical poles change by tens of per cent or more.

Clusters: a stable pole links to its partner; the links form chains through
consecutive orders, one chain per mode. Chains broken by one noisy order are merged
back when their median frequency and damping agree and they never share an order.
A cluster is rejected when
  * it is stable over fewer than ``min_stable_orders`` orders (noise and numerical poles
    come and go);
  * its median damping is <= 0 or > ``max_damping`` (spurious: a structure this
    stiff is not that damped; the paper's damped model peaks at 20 %);
  * its frequency wanders: max - min over the chain exceeds 2 x freq_tol (relative), or
    WANDER_HALF_WIDTHS of its half-power half-width (zeta f) where that is wider: a
    heavily damped mode's frequency is defined no better than a fraction of its width
    (a new user's 300 Hz mode at 8 % among 0.8-0.9 % ones, 1 % response noise: its
    chain, 6.4 %, wandered by more than 2 % and the mode was left out unsaid);
  * its frequency lies in the guard, 2 % of the band width, inside a band edge
    (there, poles stand in for modes outside the band); at the low edge the guard is
    no wider than the band's distance from 0 Hz.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment

STATUSES = ("new", "frequency", "damping", "stable")
#: The fraction of a line to which a half-power width (2 zeta f) is known.
LINE_FRACTION = 0.25


def damping_tolerance(frequency_hz, damping_ratio, damping_tol: float, line_hz: float):
    """Absolute tolerance on a damping ratio (see the module docstring); arrays broadcast."""
    with np.errstate(all="ignore"):
        return np.maximum(damping_tol * np.abs(damping_ratio), LINE_FRACTION * line_hz / frequency_hz)


def frequency_damping(poles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Undamped natural frequency (Hz) and damping ratio of poles in rad/s."""
    p = np.asarray(poles, dtype=complex)
    wn = np.abs(p)
    with np.errstate(all="ignore"):
        return wn / (2 * np.pi), np.where(wn > 0, -p.real / wn, 0.0)


def classify_order(
    prev_poles: np.ndarray,
    poles: np.ndarray,
    prev_vectors: np.ndarray | None = None,
    vectors: np.ndarray | None = None,
    freq_tol: float = 0.01,
    damping_tol: float = 0.05,
    vector_tol: float = 0.1,
    line_hz: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Status of each pole of order n against its own partner among the poles of order n-1.

    prev_poles (m,), poles (k,): complex rad/s. prev_vectors (m, n_frf), vectors
    (k, n_frf): residues, or None to skip the vector test (then "damping" never occurs).
    line_hz: line spacing, Hz, for the tolerances that scale (0: fixed percentages).
    Returns status (k,) str and partner (k,) int index into prev_poles (-1: none).
    """
    poles = np.asarray(poles, dtype=complex)
    prev_poles = np.asarray(prev_poles, dtype=complex)
    status = np.full(poles.size, "new", dtype=object)
    partner = np.full(poles.size, -1, dtype=int)
    if poles.size == 0 or prev_poles.size == 0:
        return status.astype(str), partner
    f, z = frequency_damping(poles)
    fp, zp = frequency_damping(prev_poles)
    cost = np.abs(f[:, None] - fp[None, :]) / fp[None, :]
    rows, cols = linear_sum_assignment(cost)
    close = cost[rows, cols] <= freq_tol
    rows, cols = rows[close], cols[close]
    partner[rows] = cols
    status[rows] = "frequency"
    allowed = damping_tolerance(fp[cols], zp[cols], damping_tol, line_hz)
    # Overlapping modes trade damping between them from one order to the next: where the
    # partner has a neighbour within OVERLAP half-power bandwidths, the tolerance widens.
    allowed = allowed * np.where(overlapped(fp, zp)[cols], OVERLAP_WIDENING, 1.0)
    with np.errstate(all="ignore"):
        damp_ok = np.abs(z[rows] - zp[cols]) <= allowed
        # The residue's size follows the damping: it may change by as much.
        vec_allowed = np.maximum(vector_tol, 2 * allowed / np.abs(zp[cols]))
    rows_d, cols_d = rows[damp_ok], cols[damp_ok]
    vec_allowed = vec_allowed[damp_ok]
    status[rows_d] = "damping"
    if vectors is None or prev_vectors is None:
        status[rows_d] = "stable"
    else:
        a = np.asarray(vectors)[rows_d]
        b = np.asarray(prev_vectors)[cols_d]
        with np.errstate(all="ignore"):
            change = np.linalg.norm(a - b, axis=-1) / np.linalg.norm(b, axis=-1)
        status[rows_d[change <= vec_allowed]] = "stable"
    return status.astype(str), partner


#: Two poles closer than this many of their summed half-power half-widths (zeta f) overlap ...
OVERLAP = 3.0
#: ... and the damping tolerance of each is this many times wider.
OVERLAP_WIDENING = 2.0
#: A chain's frequency may wander over its orders by this many of its half-power
#: half-widths (zeta f) where that is more than 2 x freq_tol (module docstring).
WANDER_HALF_WIDTHS = 0.5


def overlapped(frequency_hz: np.ndarray, damping_ratio: np.ndarray) -> np.ndarray:
    """(n,) bool: the pole has another of the same order within OVERLAP summed half-widths."""
    f, z = np.asarray(frequency_hz, dtype=float), np.abs(np.asarray(damping_ratio, dtype=float))
    if f.size < 2:
        return np.zeros(f.size, dtype=bool)
    width = z[:, None] * f[:, None] + z[None, :] * f[None, :]
    near = np.abs(f[:, None] - f[None, :]) < OVERLAP * width
    np.fill_diagonal(near, False)
    return near.any(axis=1)


@dataclass
class Cluster:
    """A chain of mutually stable poles across orders (one candidate mode).

    members : list of (order index, pole index). frequency_hz, damping_ratio: medians.
    n_stable_orders : number of stable links. *_scatter_rel : std / median.
    accepted : passed every rejection rule; reason says why not otherwise.
    """

    members: list[tuple[int, int]] = field(default_factory=list)
    frequency_hz: float = np.nan
    damping_ratio: float = np.nan
    frequency_scatter_rel: float = np.nan
    damping_scatter_rel: float = np.nan
    n_stable_orders: int = 0
    accepted: bool = False
    reason: str = ""

    @property
    def pole(self) -> complex:
        wn = 2 * np.pi * self.frequency_hz
        z = self.damping_ratio
        return complex(-z * wn, wn * np.sqrt(max(1.0 - z * z, 0.0)))


def stability_diagram(
    poles: list[np.ndarray],
    vectors: list[np.ndarray] | None = None,
    freq_tol: float = 0.01,
    damping_tol: float = 0.05,
    vector_tol: float = 0.1,
    line_hz: float = 0.0,
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Status (str) and partner index of every pole, order by order (first order: "new")."""
    status = [np.full(len(poles[0]), "new")]
    partner = [np.full(len(poles[0]), -1)]
    for k in range(1, len(poles)):
        s, p = classify_order(
            poles[k - 1],
            poles[k],
            None if vectors is None else vectors[k - 1],
            None if vectors is None else vectors[k],
            freq_tol,
            damping_tol,
            vector_tol,
            line_hz,
        )
        status.append(s)
        partner.append(p)
    return status, partner


def cluster_poles(
    poles: list[np.ndarray],
    status: list[np.ndarray],
    partner: list[np.ndarray],
    band: tuple[float, float],
    freq_tol: float = 0.01,
    damping_tol: float = 0.05,
    min_stable_orders: int = 5,
    max_damping: float = 0.3,
    guard: float = 0.02,
    line_hz: float = 0.0,
) -> tuple[list[Cluster], list[np.ndarray]]:
    """Chain stable poles into clusters, merge broken chains, apply the rejection rules.

    Returns the clusters (accepted or not, with reasons) and, per order, the index of
    the cluster each pole belongs to (-1: none).
    """
    label = [np.full(len(p), -1) for p in poles]
    chains: list[list[tuple[int, int]]] = []
    links: list[int] = []
    for k in range(1, len(poles)):
        for i in np.flatnonzero(status[k] == "stable"):
            j = partner[k][i]
            c = label[k - 1][j]
            if c < 0:  # the partner opens a new chain
                c = len(chains)
                chains.append([(k - 1, j)])
                links.append(0)
                label[k - 1][j] = c
            chains[c].append((k, i))
            links[c] += 1
            label[k][i] = c
    clusters = [_summarise(poles, members, n) for members, n in zip(chains, links, strict=True)]
    # Merge chains of one mode broken by a noisy order: same frequency and damping, no shared order.
    order = sorted(range(len(clusters)), key=lambda c: -clusters[c].n_stable_orders)
    target = list(range(len(clusters)))
    kept: list[int] = []
    for c in order:
        cc = clusters[c]
        for k in kept:
            ck = clusters[k]
            orders_k = {m[0] for m in ck.members}
            if (
                abs(cc.frequency_hz - ck.frequency_hz) <= freq_tol * ck.frequency_hz
                and abs(cc.damping_ratio - ck.damping_ratio)
                <= 2 * damping_tolerance(ck.frequency_hz, ck.damping_ratio, damping_tol, line_hz)
                and not orders_k.intersection(m[0] for m in cc.members)
            ):
                clusters[k] = _summarise(
                    poles, ck.members + cc.members, ck.n_stable_orders + cc.n_stable_orders
                )
                target[c] = k
                break
        else:
            kept.append(c)
    renumber = {c: n for n, c in enumerate(kept)}
    final = [clusters[c] for c in kept]
    label = [np.array([renumber[target[c]] if c >= 0 else -1 for c in lab], dtype=int) for lab in label]
    f1, f2 = band
    g = guard * (f2 - f1)
    # The low guard is never wider than the gap below the band: a band starting at the
    # first line above 0 Hz has nothing below it for edge poles to stand in for, and a
    # guard of 2 % of a 390 Hz span would throw away a beam's 5.6 Hz first mode.
    low_guard = min(g, f1)
    for c in final:
        freqs, _ = frequency_damping(np.array([poles[k][i] for k, i in c.members]))
        if c.n_stable_orders < min_stable_orders:
            c.reason = f"stable over {c.n_stable_orders} < {min_stable_orders} orders"
        elif not 0.0 < c.damping_ratio <= max_damping:
            c.reason = f"damping {c.damping_ratio:.3g} outside (0, {max_damping}]"
        elif np.ptp(freqs) > max(2 * freq_tol, WANDER_HALF_WIDTHS * c.damping_ratio) * c.frequency_hz:
            c.reason = "frequency wanders across orders"
        elif c.frequency_hz < f1 + low_guard or c.frequency_hz > f2 - g:
            c.reason = "inside the band-edge guard"
        else:
            c.accepted = True
    # Two accepted chains closer than the smaller half-power half-width (zeta f) are one
    # mode split at some orders into two poles: keep the chain stable over more orders.
    kept_modes: list[Cluster] = []
    for c in sorted((c for c in final if c.accepted), key=lambda c: -c.n_stable_orders):
        for k in kept_modes:
            width = max(min(c.damping_ratio, k.damping_ratio) * k.frequency_hz, line_hz)
            if abs(c.frequency_hz - k.frequency_hz) < width:
                c.accepted, c.reason = False, "duplicate of a chain stable over more orders"
                break
        else:
            kept_modes.append(c)
    return final, label


def _summarise(poles: list[np.ndarray], members: list[tuple[int, int]], n_links: int) -> Cluster:
    p = np.array([poles[k][i] for k, i in members])
    f, z = frequency_damping(p)
    fm, zm = float(np.median(f)), float(np.median(z))
    return Cluster(
        members=sorted(members),
        frequency_hz=fm,
        damping_ratio=zm,
        frequency_scatter_rel=float(np.std(f) / fm),
        damping_scatter_rel=float(np.std(z) / abs(zm)) if zm != 0 else np.inf,
        n_stable_orders=n_links,
    )


def pick_clusters(
    clusters: list[Cluster],
    frequencies_hz: np.ndarray | None = None,
    near: float = 0.05,
    line_hz: float = 0.0,
) -> list[int]:
    """Indices of the selected clusters, sorted by frequency.

    Without frequencies of interest: every accepted cluster. With them, for each
    frequency: the nearest cluster within ``near`` (relative) with a physical damping
    that is accepted or stable over at least ASKED_MIN_LINKS links, an accepted one
    preferred where it lies no more than its half-power half-width (zeta f, at least a
    line ``line_hz``, Hz) farther; else the nearest cluster with a physical damping;
    each cluster at most once. Accepted clusters elsewhere in the band do not hide a
    weaker cluster at a frequency asked for, and an accepted chain between two close
    modes (a blend of both) is not taken for the one asked for when the mode's own
    chain lies at it (31.96 Hz at 0.78 % was returned for 33 Hz, between modes at 31
    and 33 Hz, where a chain at 33.02 Hz fell one order short of acceptance).
    """
    accepted = [i for i, c in enumerate(clusters) if c.accepted]
    if frequencies_hz is None:
        return sorted(accepted, key=lambda i: clusters[i].frequency_hz)
    physical = [i for i, c in enumerate(clusters) if c.damping_ratio > 0]
    chosen: list[int] = []
    for f in np.atleast_1d(frequencies_hz):

        def dist(i: int, f: float = float(f)) -> float:
            return abs(clusters[i].frequency_hz - f)

        held = [
            i
            for i in physical
            if i not in chosen
            and dist(i) <= near * f
            and (clusters[i].accepted or clusters[i].n_stable_orders >= ASKED_MIN_LINKS)
        ]
        if held:
            best = min(held, key=lambda i: (dist(i), -clusters[i].n_stable_orders))
            held_accepted = [i for i in held if clusters[i].accepted]
            if held_accepted and not clusters[best].accepted:
                a = min(held_accepted, key=dist)
                width = max(clusters[a].damping_ratio * clusters[a].frequency_hz, line_hz)
                if dist(a) <= dist(best) + width:
                    best = a
            chosen.append(best)
            continue
        rest = [i for i in physical if i not in chosen]
        if rest:
            chosen.append(min(rest, key=dist))
    return sorted(chosen, key=lambda i: clusters[i].frequency_hz)


#: A cluster that failed a selection rule is taken for a frequency asked for only when it
#: is stable over at least this many links (one link is two poles that happen to agree).
ASKED_MIN_LINKS = 2

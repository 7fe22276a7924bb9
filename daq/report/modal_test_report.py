"""The report of a multi-point modal test (roving hammer or roving sensor along a beam):
PNG figures and one self-contained HTML page, drawn from a `ModalTestReport` that the
caller fills with results already computed. Nothing is analysed here: the only
arithmetic is what a plot needs (the sum of |FRF| behind the stability diagram, the
exact shape read at the points to choose the sign of a measured shape).

Every text that comes from the data (test, article, point and FRF names, notes,
cautions) is HTML-escaped on the page and has its ``$`` escaped in the figures (a point
named ``$x$`` must not switch matplotlib into mathtext)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from analysis.modal_id import DENOMINATOR, NORMALISATIONS
from daq.report.figures import STATUS_STYLE, _png, _pyplot
from daq.report.numbers import plain, with_uncertainty
from daq.report.page import STYLE, _cautions, _e, _img, _num, _table

#: Stability status of a pole -> the code of figures.STATUS_STYLE whose marker and colour
#: it takes (the run report's look), and its label here.
STABILITY_STATUS = {
    "new": (0, "new pole"),
    "frequency": (1, "frequency stable"),
    "stable": (3, "stable"),
}
STD_LABEL = "± is the standard uncertainty (one standard deviation)"


@dataclass
class ModalTestReport:
    """The results of one modal test, as plain data (numpy arrays), ready to draw.

    Test and article
        test_name: the test's name. article: a description of the test article.
        point_names (n_points,) str: the measurement points' names (user input).
        point_positions_m (n_points,): each point's distance from the clamp, m.
        beam_length_m: the beam's length, m. fixed_point: the name of the point that
        does not move (the sensor for a roving hammer, the hammer for a roving sensor).

    FRFs
        frequency_hz (n_lines,): the lines, Hz. measured_frf and synthesized_frf
        (n_frf, n_lines) complex: each FRF as measured and as synthesised from the
        identified modes, in ``frf_unit`` (a label such as ``(m/s²)/N``).
        frf_labels (n_frf,) str: e.g. ``"force p3 -> sensor tip"``.

    Stability diagram
        stability: the poles of every model order, either a sequence of
        ``(order: int, frequency_hz: float, status: str)`` or a mapping with the arrays
        ``"order"``, ``"frequency_hz"`` and ``"status"``; status is one of ``"stable"``,
        ``"frequency"`` (frequency stable only) and ``"new"``. The mapping may also hold
        ``"normalisation"``: the LSCF normalisation of the fit each pole is from (one of
        analysis.modal_id.NORMALISATIONS); the diagram then has one panel per fit.
        selected_frequencies_hz: the modes chosen on the diagram, Hz (None: the modes'
        ``mode_frequency_hz``).
        set_aside_hz: the possible modes left out that a caution names, Hz, drawn as
        dashed lines (None or empty: none).

    Modes (n_modes of them)
        mode_frequency_hz, mode_frequency_std_hz: natural frequency and its standard
        uncertainty, Hz. damping_ratio, damping_std: the damping ratio and its standard
        uncertainty, fractions of critical (0.01 is 1 %). mpc: modal phase collinearity
        (0-1).
        shapes (n_modes, n_points) complex: the mode shapes at the points, scaled as
        ``shape_scaling`` says (e.g. ``"unit modal mass (1/√kg), through the driving
        point p7"``). shape_std (n_modes, n_points): the standard uncertainty of the
        real part of each shape value, same unit.

    The beam's own shapes
        grid_m (n_grid,): positions from the clamp, m. exact_shapes (n_modes, n_grid):
        the exact beam's shape paired with each measured mode, same scaling as
        ``shapes``. ritz_shapes (n_modes, n_grid) or None: the Ritz model's.
        mac_exact (n_modes, n_modes_exact): MAC of each measured shape against each
        exact beam mode; mac_ritz (n_modes, n_modes_ritz) or None; auto_mac
        (n_modes, n_modes): the measured shapes against each other.

    Damping fit (optional)
        fit_method: how R was fitted, or None when it was not. damping_matrix (N, N):
        the fitted R, N s/m. damping_matrix_std (N, N): the standard uncertainty of
        each term, N s/m (None: not stated). fit_notes: which terms and combinations
        the data determine and which not, one sentence each.

    cautions: what the reader must know before trusting the page, one sentence each.
    """

    test_name: str
    article: str
    point_names: np.ndarray
    point_positions_m: np.ndarray
    beam_length_m: float
    fixed_point: str
    frequency_hz: np.ndarray
    measured_frf: np.ndarray
    synthesized_frf: np.ndarray
    frf_labels: np.ndarray
    frf_unit: str
    stability: Sequence[tuple[int, float, str]] | Mapping[str, np.ndarray]
    mode_frequency_hz: np.ndarray
    mode_frequency_std_hz: np.ndarray
    damping_ratio: np.ndarray
    damping_std: np.ndarray
    mpc: np.ndarray
    shapes: np.ndarray
    shape_std: np.ndarray
    shape_scaling: str
    grid_m: np.ndarray
    exact_shapes: np.ndarray
    mac_exact: np.ndarray
    auto_mac: np.ndarray
    ritz_shapes: np.ndarray | None = None
    mac_ritz: np.ndarray | None = None
    selected_frequencies_hz: np.ndarray | None = None
    set_aside_hz: np.ndarray | None = None
    fit_method: str | None = None
    damping_matrix: np.ndarray | None = None
    damping_matrix_std: np.ndarray | None = None
    fit_notes: list[str] = field(default_factory=list)
    cautions: list[str] = field(default_factory=list)
    #: How the points' records were analysed, where not whole (hits cut at their impacts).
    records_note: str = ""
    #: (n_modes,) the exact beam mode (0-based, -1: none) each measured mode is paired
    #: with (Table 2 of a test: nearest in frequency); None: the mode of the same number.
    paired_exact_mode: np.ndarray | None = None


def render_modal_test_report(report: ModalTestReport) -> tuple[str, dict[str, bytes]]:
    """(index.html text, {figure name: PNG bytes}) of ``report``, like
    daq.report.build.build_report: the page embeds every figure, and the figures are
    also returned to be written beside it. ValueError when the arrays disagree in shape."""
    _check(report)
    pngs = {
        "stability": stability_figure(report),
        "mode_shapes": mode_shapes_figure(report),
        "mac": mac_figure(report),
        "frf": frf_figure(report),
    }
    return render_page(report, pngs), pngs


# ---------------------------------------------------------------------------- checks


def _check(r: ModalTestReport) -> None:
    n_points = len(r.point_names)
    n_modes = len(r.mode_frequency_hz)
    n_lines = len(r.frequency_hz)
    n_frf = len(r.frf_labels)
    n_grid = len(r.grid_m)
    expected: dict[str, tuple[Any, tuple[int | None, ...]]] = {
        "point_positions_m": (r.point_positions_m, (n_points,)),
        "measured_frf": (r.measured_frf, (n_frf, n_lines)),
        "synthesized_frf": (r.synthesized_frf, (n_frf, n_lines)),
        "mode_frequency_std_hz": (r.mode_frequency_std_hz, (n_modes,)),
        "damping_ratio": (r.damping_ratio, (n_modes,)),
        "damping_std": (r.damping_std, (n_modes,)),
        "mpc": (r.mpc, (n_modes,)),
        "shapes": (r.shapes, (n_modes, n_points)),
        "shape_std": (r.shape_std, (n_modes, n_points)),
        "exact_shapes": (r.exact_shapes, (n_modes, n_grid)),
        "ritz_shapes": (r.ritz_shapes, (n_modes, n_grid)),
        "mac_exact": (r.mac_exact, (n_modes, None)),
        "mac_ritz": (r.mac_ritz, (n_modes, None)),
        "auto_mac": (r.auto_mac, (n_modes, n_modes)),
    }
    for name, (value, shape) in expected.items():
        if value is None:
            continue
        actual = np.shape(value)
        if len(actual) != len(shape) or any(
            s is not None and a != s for a, s in zip(actual, shape, strict=True)
        ):
            want = "x".join("any" if s is None else str(s) for s in shape)
            raise ValueError(f"modal test report: {name} has shape {actual}, expected {want}")
    if r.damping_matrix is not None:
        n = np.shape(r.damping_matrix)
        if len(n) != 2 or n[0] != n[1]:
            raise ValueError(f"modal test report: damping_matrix has shape {n}, expected N x N")
        if r.damping_matrix_std is not None and np.shape(r.damping_matrix_std) != n:
            raise ValueError(
                f"modal test report: damping_matrix_std has shape {np.shape(r.damping_matrix_std)}, "
                f"expected {n[0]}x{n[1]}"
            )
    _stability_arrays(r.stability)  # raises on an unknown status


def _stability_arrays(stability: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if isinstance(stability, Mapping):
        order = np.asarray(stability["order"], dtype=int)
        freq = np.asarray(stability["frequency_hz"], dtype=float)
        status = np.asarray(stability["status"], dtype=str)
        fits = stability.get("normalisation")
        if fits is not None and (
            np.shape(fits) != order.shape or not set(np.asarray(fits, str)) <= set(NORMALISATIONS)
        ):
            raise ValueError(
                "modal test report: stability normalisation must name one of "
                f"{', '.join(NORMALISATIONS)} per pole"
            )
    else:
        rows = list(stability)
        order = np.array([int(o) for o, _, _ in rows], dtype=int)
        freq = np.array([float(f) for _, f, _ in rows], dtype=float)
        status = np.array([str(s) for _, _, s in rows], dtype=str)
    unknown = sorted(set(status.tolist()) - set(STABILITY_STATUS))
    if unknown:
        raise ValueError(
            f"modal test report: stability status {unknown[0]!r} is none of {', '.join(STABILITY_STATUS)}"
        )
    return order, freq, status


# --------------------------------------------------------------------------- figures


def _t(text: Any) -> str:
    """A text from the data as matplotlib shows it literally (no mathtext)."""
    return str(text).replace("$", r"\$")


def _selected(r: ModalTestReport) -> np.ndarray:
    chosen = r.mode_frequency_hz if r.selected_frequencies_hz is None else r.selected_frequencies_hz
    return np.asarray(chosen, dtype=float)


def stability_figure(r: ModalTestReport) -> bytes:
    """The poles of every model order by status, over the sum of |FRF| of all FRFs."""
    plt = _pyplot()
    order, freq, status = _stability_arrays(r.stability)
    fits = r.stability.get("normalisation") if isinstance(r.stability, Mapping) else None
    fits = None if fits is None else np.asarray(fits, dtype=str)
    # One panel per LSCF fit (every zone is fitted with each normalisation), in their order.
    panels = [None] if fits is None else [n for n in NORMALISATIONS if np.any(fits == n)] or [None]
    f = np.asarray(r.frequency_hz, dtype=float)
    fig, axes = plt.subplots(1, len(panels), figsize=(10 if len(panels) == 1 else 14, 5), sharey=True,
                             squeeze=False)  # fmt: skip
    for ax, panel in zip(axes[0], panels, strict=True):
        mine = np.ones(order.size, dtype=bool) if panel is None else fits == panel
        for name, (code, label) in STABILITY_STATUS.items():
            pick = mine & (status == name)
            if pick.any():
                _, marker, colour = STATUS_STYLE[code]
                ax.scatter(freq[pick], order[pick], marker=marker, s=18, color=colour, label=label)
        for k, fk in enumerate(_selected(r)):
            ax.axvline(fk, color="#1b7a2f", lw=0.8, alpha=0.6, label="selected mode" if k == 0 else None)
        for k, fk in enumerate(np.asarray(r.set_aside_hz if r.set_aside_hz is not None else [], dtype=float)):
            # The possible modes left out that a caution names (analysis.modal_id.identify.SetAside).
            ax.axvline(fk, color="#d35400", lw=0.9, ls="--",
                       label="possible mode left out (see the cautions)" if k == 0 else None)  # fmt: skip
        ax.set_xlabel("frequency (Hz)")
        twin = ax.twinx()
        twin.semilogy(f, np.abs(np.atleast_2d(r.measured_frf)).sum(axis=0), color="#555555", lw=0.8)
        if ax is axes[0][-1]:
            twin.set_ylabel(_t(f"sum of |H| over {len(r.frf_labels)} FRFs ({r.frf_unit})"))
        ax.set_xlim(f[0], f[-1])
        if panel is not None:
            ax.set_title(f"LSCF with {DENOMINATOR[panel]}", fontsize=9)
    axes[0][0].set_ylabel("model order")
    axes[0][0].legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=4, fontsize=7, frameon=False)
    fig.suptitle(
        _t(f"Test {r.test_name}: stability diagram over all FRFs, {len(_selected(r))} modes selected")
    )
    return _png(fig)


def _sign_to_exact(r: ModalTestReport, k: int) -> float:
    """+1 or -1: the sign that turns measured shape k the way the exact beam's is."""
    exact_at_points = np.interp(r.point_positions_m, r.grid_m, np.real(r.exact_shapes[k]))
    dot = float(np.dot(np.real(r.shapes[k]), exact_at_points))
    return -1.0 if dot < 0 else 1.0


def mode_shapes_figure(r: ModalTestReport) -> bytes:
    """A sketch of the beam with its points, then each mode along the beam: the measured
    real part at the points with ±1 standard uncertainty, sign-aligned to the exact
    beam's shape, beside the exact and Ritz shapes."""
    plt = _pyplot()
    n_modes = len(r.mode_frequency_hz)
    fig, axes = plt.subplots(
        n_modes + 1, 1, figsize=(10, 2.6 * n_modes + 1.8), sharex=True, squeeze=False,
        gridspec_kw={"height_ratios": [0.45] + [1.0] * n_modes},
    )  # fmt: skip
    axes = axes[:, 0]
    x = np.asarray(r.point_positions_m, dtype=float)
    _beam_sketch(axes[0], r, x)
    for k in range(n_modes):
        ax = axes[k + 1]
        sign = _sign_to_exact(r, k)
        ax.plot(r.grid_m, np.real(r.exact_shapes[k]), color="#555555", lw=1.2, label="exact beam")
        if r.ritz_shapes is not None:
            ax.plot(r.grid_m, np.real(r.ritz_shapes[k]), color="#c0392b", lw=1.0, ls="--", label="Ritz")
        ax.errorbar(
            x, sign * np.real(r.shapes[k]), yerr=np.asarray(r.shape_std[k], dtype=float),
            fmt="o", ms=5, color="#1f4e9c", ecolor="#1f4e9c", capsize=3, lw=1.0,
            label="measured (real part), ±1 standard uncertainty",
        )  # fmt: skip
        ax.axhline(0, color="#999999", lw=0.6)
        ax.set_ylabel(f"mode {k + 1}", fontsize=9)
        ax.grid(alpha=0.3)
        ax.set_title(
            f"mode {k + 1}: {plain(r.mode_frequency_hz[k], '.4g')} Hz, MPC {r.mpc[k]:.3f}"
            + ("" if sign > 0 else " (measured sign flipped to match the exact shape)"),
            fontsize=9,
            loc="left",
        )
    axes[-1].legend(loc="upper center", bbox_to_anchor=(0.5, -0.28), ncol=3, fontsize=8, frameon=False)
    axes[-1].set_xlabel("distance from the clamp (m)")
    axes[-1].set_xlim(-0.03 * r.beam_length_m, 1.02 * r.beam_length_m)
    fig.suptitle(_t(f"Test {r.test_name}: mode shapes, {r.shape_scaling}"))
    return _png(fig)


def _beam_sketch(ax: Any, r: ModalTestReport, x: np.ndarray) -> None:
    """The beam from its clamp, each point marked and named, the fixed point in red."""
    from matplotlib.patches import Rectangle

    length = r.beam_length_m
    ax.add_patch(Rectangle((-0.025 * length, -0.6), 0.025 * length, 1.2, hatch="///", fill=False, lw=0.8))
    ax.plot([0, length], [0, 0], color="#777777", lw=5, solid_capstyle="butt")
    fixed = np.array([str(name) == str(r.fixed_point) for name in r.point_names])
    ax.scatter(x[~fixed], np.zeros((~fixed).sum()), marker="v", s=30, color="#1f4e9c", zorder=3)
    ax.scatter(x[fixed], np.zeros(fixed.sum()), marker="*", s=90, color="#c0392b", zorder=3)
    for xk, name, is_fixed in zip(x, r.point_names, fixed, strict=True):
        ax.text(xk, 0.45, _t(name) + (" (fixed)" if is_fixed else ""), rotation=30, fontsize=7,
                ha="left", va="bottom", color="#c0392b" if is_fixed else "#222222")  # fmt: skip
    ax.set_ylim(-0.8, 1.8)
    ax.set_yticks([])
    for side in ("left", "right", "top"):
        ax.spines[side].set_visible(False)
    where = "" if fixed.any() else f"; fixed point {r.fixed_point} (not one of these points)"
    ax.set_title(_t(f"{len(x)} points along the beam{where}"), fontsize=9, loc="left")


def _mac_axes(fig: Any, ax: Any, matrix: np.ndarray, title: str, xlabel: str) -> None:
    m = np.asarray(matrix, dtype=float)
    image = ax.imshow(m, cmap="Blues", vmin=0, vmax=1, origin="upper", aspect="auto")
    size = 9 if max(m.shape) <= 8 else 7
    for i in range(m.shape[0]):
        for j in range(m.shape[1]):
            ax.text(j, i, f"{m[i, j]:.2f}", ha="center", va="center", fontsize=size,
                    color="white" if m[i, j] > 0.6 else "black")  # fmt: skip
    ax.set_xticks(range(m.shape[1]), [str(j + 1) for j in range(m.shape[1])])
    ax.set_yticks(range(m.shape[0]), [str(i + 1) for i in range(m.shape[0])])
    ax.set_xlabel(xlabel)
    ax.set_ylabel("measured mode")
    ax.set_title(title, fontsize=10)
    fig.colorbar(image, ax=ax, fraction=0.046, pad=0.04)


def mac_figure(r: ModalTestReport) -> bytes:
    """The MAC against the exact beam (and the Ritz model), and the auto-MAC, each as a
    heat map with its numbers written in the cells."""
    plt = _pyplot()
    panels = [(r.mac_exact, "MAC: measured vs exact beam", "beam mode (exact)")]
    if r.mac_ritz is not None:
        panels.append((r.mac_ritz, "MAC: measured vs Ritz model", "beam mode (Ritz)"))
    panels.append((r.auto_mac, "auto-MAC of the measured shapes", "measured mode"))
    fig, axes = plt.subplots(1, len(panels), figsize=(4.8 * len(panels), 4.2), squeeze=False)
    for ax, (matrix, title, xlabel) in zip(axes[0], panels, strict=True):
        _mac_axes(fig, ax, matrix, title, xlabel)
    fig.suptitle(_t(f"Test {r.test_name}: modal assurance criterion"))
    fig.tight_layout()
    return _png(fig)


def frf_figure(r: ModalTestReport) -> bytes:
    """|H| measured and synthesised of every FRF, one small panel each."""
    plt = _pyplot()
    n = len(r.frf_labels)
    cols = min(3, n)
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 2.4 * rows + 0.8), squeeze=False, sharex=True)
    f = np.asarray(r.frequency_hz, dtype=float)
    for k in range(rows * cols):
        ax = axes.flat[k]
        if k >= n:
            ax.set_visible(False)
            continue
        ax.semilogy(f, np.abs(r.measured_frf[k]), color="#1f4e9c", lw=0.8, label="measured")
        ax.semilogy(f, np.abs(r.synthesized_frf[k]), color="#c0392b", lw=0.8, ls="--", label="synthesised")
        ax.set_title(_t(r.frf_labels[k]), fontsize=8, loc="left")
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3, which="both")
        if k % cols == 0:
            ax.set_ylabel(_t(f"|H| ({r.frf_unit})"), fontsize=8)
        if k >= n - cols:
            ax.set_xlabel("frequency (Hz)", fontsize=8)
    axes.flat[0].legend(fontsize=7)
    fig.suptitle(_t(f"Test {r.test_name}: measured and synthesised FRFs ({n})"))
    fig.subplots_adjust(hspace=0.4, wspace=0.3)  # not tight_layout: it measures every log tick again
    return _png(fig)


# ------------------------------------------------------------------------------ page


def _td(text: str) -> str:
    return f"<td class='num'>{text}</td>"


def render_page(r: ModalTestReport, figures: dict[str, bytes]) -> str:
    """The page of ``r`` with its ``figures`` (name -> PNG) embedded."""
    info = [
        ("test", r.test_name), ("article", r.article), ("beam length", f"{plain(r.beam_length_m, '.4g')} m"),
        ("fixed point", r.fixed_point), ("points", len(r.point_names)), ("FRFs", len(r.frf_labels)),
        ("shape scaling", r.shape_scaling),
    ]  # fmt: skip
    if r.records_note:
        info.append(("records", r.records_note))
    parts = [
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
        f"<title>Modal test {_e(r.test_name)}</title><style>{STYLE}"
        ".cautions { margin: 1em 0; }</style></head><body>",
        f"<h1>Modal test {_e(r.test_name)}</h1>",
    ]
    if r.cautions:
        parts += ["<div class='cautions'>", *_cautions(list(r.cautions)), "</div>"]
    parts.append(_table(["", ""], [[f"<th>{_e(k)}</th>", f"<td>{_e(v)}</td>"] for k, v in info]))

    parts.append("<h2>Points</h2>")
    point_rows = [
        [f"<td>{_e(name)}</td>", _td(plain(float(x), ".4g")),
         "<td>fixed</td>" if str(name) == str(r.fixed_point) else "<td></td>"]
        for name, x in zip(r.point_names, r.point_positions_m, strict=True)
    ]  # fmt: skip
    parts.append(_table(["point", "distance from the clamp (m)", ""], point_rows))

    parts += ["<h2>Modes</h2>", f"<p class='note'>{_e(STD_LABEL)}.</p>"]
    n_exact = np.shape(r.mac_exact)[1]
    mode_rows = []
    for k in range(len(r.mode_frequency_hz)):
        if r.paired_exact_mode is not None:
            j = int(r.paired_exact_mode[k])
            mac = float(r.mac_exact[k][j]) if 0 <= j < n_exact else None
        else:
            mac = float(r.mac_exact[k][k]) if k < n_exact else None
        mode_rows.append([
            _td(str(k + 1)),
            _td(" ± ".join(with_uncertainty(r.mode_frequency_hz[k], r.mode_frequency_std_hz[k], ".4f"))),
            _td(" ± ".join(with_uncertainty(100 * r.damping_ratio[k], 100 * r.damping_std[k], ".3g"))),
            _td(f"{r.mpc[k]:.3f}"), _td(_num(mac, ".3f")),
        ])  # fmt: skip
    header = [
        "mode", "frequency (Hz) ± std. uncertainty", "damping (%) ± std. uncertainty", "MPC",
        "MAC vs its exact beam mode" if r.paired_exact_mode is not None
        else "MAC vs exact beam mode of the same number",
    ]  # fmt: skip
    parts.append(_table(header, mode_rows))

    parts += ["<h2>Stability diagram</h2>", _img(figures["stability"], "stability diagram over all FRFs")]

    parts.append("<h2>Mode shapes</h2>")
    ritz = (
        "beside the exact beam's (solid) and the Ritz model's (dashed) shapes"
        if r.ritz_shapes is not None
        else "beside the exact beam's shapes (Ritz shapes: not given)"
    )
    parts.append(
        f"<p class='note'>Measured real part at each point ({_e(r.shape_scaling)}), error bars ±1 "
        f"standard uncertainty, sign-aligned to the exact shape, {_e(ritz)}.</p>"
    )
    parts.append(_img(figures["mode_shapes"], "mode shapes along the beam"))

    parts.append("<h2>MAC</h2>")
    if r.mac_ritz is None:
        parts.append("<p class='note'>MAC against the Ritz model: not given.</p>")
    parts.append(_img(figures["mac"], "MAC matrix"))

    parts += _fit_section(r)

    parts += ["<h2>FRFs</h2>", _img(figures["frf"], "measured and synthesised FRFs")]
    parts.append("</body></html>")
    return "\n".join(parts)


def _fit_section(r: ModalTestReport) -> list[str]:
    parts = ["<h2>Damping matrix</h2>"]
    if r.damping_matrix is None:
        return [*parts, "<p class='note'>Damping matrix: not fitted.</p>"]
    big_r = np.asarray(r.damping_matrix, dtype=float)
    std = None if r.damping_matrix_std is None else np.asarray(r.damping_matrix_std, dtype=float)
    parts.append(
        f"<p>Method: <b>{_e(r.fit_method or 'not stated')}</b>. R in N s/m; {_e(STD_LABEL)}"
        + ("" if std is not None else " (not stated for this fit)")
        + ".</p>"
    )
    rows = []
    for i in range(big_r.shape[0]):
        cells = [f"<th>{i + 1}</th>"]
        for j in range(big_r.shape[1]):
            spread = "–" if std is None else plain(std[i, j], ".2g")
            cells.append(_td(f"{plain(big_r[i, j], '.4g')} ± {spread}"))
        rows.append(cells)
    header = ["R (N s/m) ± std. uncertainty", *[str(j + 1) for j in range(big_r.shape[1])]]
    parts.append(_table(header, rows))
    parts += [f"<p class='note'>{_e(note)}</p>" for note in r.fit_notes]
    return parts

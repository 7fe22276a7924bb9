"""The report of a multi-point modal test (daq/report/modal_test_report.py), drawn from
synthetic results: 7 points along a 0.45 m cantilever, 3 modes with the closed-form
cantilever shapes, a roving hammer and the sensor at the tip."""

from __future__ import annotations

import base64
import dataclasses
import html
import re

import numpy as np
import pytest

from daq.report import modal_test_report as mtr
from daq.report.modal_test_report import ModalTestReport, render_modal_test_report

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
LENGTH_M = 0.45
#: beta_n L of a clamped-free beam (roots of 1 + cos cosh = 0), written out.
BETA_L = np.array([1.8751040687, 4.6940911330, 7.8547574382])
EVIL_NAME = "<script>alert(1)</script>"


def _cantilever(x: np.ndarray) -> np.ndarray:
    """(3, len(x)) closed-form cantilever shapes, tip value 2 (unit-modal-mass up to a factor)."""
    b = BETA_L[:, None] / LENGTH_M
    sigma = (np.cosh(BETA_L) + np.cos(BETA_L)) / (np.sinh(BETA_L) + np.sin(BETA_L))
    bx = b * x[None, :]
    return np.cosh(bx) - np.cos(bx) - sigma[:, None] * (np.sinh(bx) - np.sin(bx))


def _mac(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    num = np.abs(a.conj() @ b.T) ** 2
    return num / np.outer(np.sum(np.abs(a) ** 2, axis=1), np.sum(np.abs(b) ** 2, axis=1))


def _report(**changes) -> ModalTestReport:
    rng = np.random.default_rng(3)
    positions = np.linspace(LENGTH_M / 7, LENGTH_M, 7)
    names = np.array([f"p{k + 1}" for k in range(6)] + [EVIL_NAME])
    grid = np.linspace(0, LENGTH_M, 200)
    exact_at_points = _cantilever(positions)
    # Measured: the exact shapes with a little noise, a small imaginary part, mode 2 of
    # the opposite sign (the drawing must turn it round).
    shapes = exact_at_points * (1 + 0.02 * rng.standard_normal(exact_at_points.shape))
    shapes = shapes + 0.01j * rng.standard_normal(shapes.shape)
    shapes[1] *= -1
    f_modes = np.array([11.3, 70.8, 198.2])
    zeta = np.array([0.012, 0.008, 0.006])
    f = np.linspace(1, 250, 500)
    s = 2j * np.pi * f
    # Roving hammer, sensor at the tip: H_j = sum_r phi_r(tip) phi_r(x_j) s^2 / (s^2 + 2 zeta w s + w^2)
    w = 2 * np.pi * f_modes[:, None]
    modal = s**2 / (s**2 + 2 * zeta[:, None] * w * s + w**2)
    synthesized = np.einsum("r,rj,rl->jl", exact_at_points[:, -1], exact_at_points, modal)
    measured = synthesized * (1 + 0.03 * rng.standard_normal(synthesized.shape))
    stability = []
    for order in range(2, 31, 2):
        for fk in f_modes[: min(3, order // 4 + 1)]:
            status = "stable" if order >= 12 else ("frequency" if order >= 6 else "new")
            stability.append((order, float(fk * (1 + 0.002 * rng.standard_normal())), status))
        stability.append((order, float(rng.uniform(1, 250)), "new"))
    exact_grid = _cantilever(grid)
    values = {
        "test_name": "beam <A&B>",
        "article": "steel cantilever 450 x 25 x 3 mm",
        "point_names": names,
        "point_positions_m": positions,
        "beam_length_m": LENGTH_M,
        "fixed_point": EVIL_NAME,
        "frequency_hz": f,
        "measured_frf": measured,
        "synthesized_frf": synthesized,
        "frf_labels": np.array([f"force {n} -> sensor {EVIL_NAME}" for n in names]),
        "frf_unit": "(m/s²)/N",
        "stability": stability,
        "mode_frequency_hz": f_modes,
        "mode_frequency_std_hz": np.array([0.004, 0.02, 0.05]),
        "damping_ratio": zeta,
        "damping_std": np.array([0.0004, 0.0003, 0.0005]),
        "mpc": np.array([0.998, 0.995, 0.990]),
        "shapes": shapes,
        "shape_std": np.full(shapes.shape, 0.03),
        "shape_scaling": "unit modal mass (1/√kg), through the driving point",
        "grid_m": grid,
        "exact_shapes": exact_grid,
        "ritz_shapes": exact_grid * 1.01,
        "mac_exact": _mac(shapes, _cantilever(positions)),
        "mac_ritz": _mac(shapes, _cantilever(positions))[:, :2],
        "auto_mac": _mac(shapes, shapes),
        "fit_method": "least squares over 7 points",
        "damping_matrix": np.array([[0.12, -0.03, 0.01], [-0.03, 0.25, 0.02], [0.01, 0.02, 0.4]]),
        "damping_matrix_std": np.array([[0.002, 0.004, 0.006], [0.004, 0.01, 0.02], [0.006, 0.02, 0.05]]),
        "fit_notes": ["R13 + 0.4 R33 is determined to 1 %; R13 - R33 is not <determined>"],
        "cautions": ["point p4 has coherence below 0.8 between 60 and 80 Hz <b>", "only 3 hits at p6"],
    }
    values.update(changes)
    return ModalTestReport(**values)


def _figures_in_page(page: str, pngs: dict[str, bytes]) -> None:
    for name, png in pngs.items():
        assert png.startswith(PNG_SIGNATURE), name
        assert len(png) > 10_000, name  # a drawn figure, not an empty canvas
        assert base64.b64encode(png).decode("ascii") in page, f"{name} is not embedded in the page"
    assert page.count('src="data:image/png;base64,') == len(pngs)
    assert not re.search(r'(src|href)="(https?:|//)', page)


def test_the_page_holds_every_section_figure_caution_and_the_r_table(drawn):
    _, page, pngs, _ = drawn
    assert set(pngs) == {"stability", "mode_shapes", "mac", "frf"}
    _figures_in_page(page, pngs)
    for heading in ("Points", "Modes", "Stability diagram", "Mode shapes", "MAC", "Damping matrix", "FRFs"):
        assert f"<h2>{heading}</h2>" in page
    # Cautions on top, before the first section, each with the run report's prefix.
    cautions = page.index("caution: point p4 has coherence below 0.8 between 60 and 80 Hz &lt;b&gt;")
    assert cautions < page.index("<h2>")
    assert "caution: only 3 hits at p6" in page
    # The fitted R with its standard uncertainty, every term.
    assert "least squares over 7 points" in page
    assert "0.12 ± 0.002" in page
    assert "-0.03 ± 0.004" in page
    assert "0.4 ± 0.05" in page
    assert "R (N s/m) ± std. uncertainty" in page
    assert "R13 - R33 is not &lt;determined&gt;" in page
    assert "± is the standard uncertainty" in page
    # Every ± on the page is labelled: each table header that has one says so.
    for header in re.findall(r"<th>([^<]*±[^<]*)</th>", page):
        assert "std. uncertainty" in header
    assert "11.3000 ± 0.0040" in page  # mode 1's frequency, to the place of its u
    assert "1.200 ± 0.040" in page  # mode 1's damping in %, to the place of its u
    assert "not fitted" not in page


def test_strings_from_the_data_are_escaped(drawn):
    page = drawn[1]
    assert "<script>" not in page
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in page
    assert "Modal test beam &lt;A&amp;B&gt;" in page
    assert "<b>" not in page.split("</style>")[1].replace("<b>least", "")  # only the page's own bold


def test_without_ritz_shapes_or_fit_the_page_says_so():
    report = _report(
        ritz_shapes=None, mac_ritz=None, fit_method=None, damping_matrix=None,
        damping_matrix_std=None, fit_notes=[], cautions=[],
    )  # fmt: skip
    page, pngs = render_modal_test_report(report)
    _figures_in_page(page, pngs)
    assert "Damping matrix: not fitted." in page
    assert "Ritz shapes: not given" in page
    assert "MAC against the Ritz model: not given" in page
    assert "caution:" not in page
    assert "<div class='cautions'>" not in page


def test_a_fit_without_stated_uncertainty_still_renders(drawn):
    page = mtr.render_page(_report(damping_matrix_std=None), drawn[2])
    assert "0.12 ± –" in page
    assert "not stated for this fit" in page


@pytest.fixture(scope="module")
def drawn():
    """The full report rendered once: (report, page, pngs, every matplotlib figure drawn,
    kept readable after the report closed it)."""
    report = _report()
    figures = []
    real_png = mtr._png

    def keep(fig):
        figures.append(fig)
        return real_png(fig)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(mtr, "_png", keep)
        page, pngs = render_modal_test_report(report)
    return report, page, pngs, figures


def test_the_mac_numbers_are_written_in_the_cells(drawn):
    report, _, _, figures = drawn
    (fig,) = [f for f in figures if "assurance" in f.get_suptitle()]
    panels = {ax.get_title(): ax for ax in fig.axes if ax.get_title()}
    matrices = {
        "MAC: measured vs exact beam": report.mac_exact,
        "MAC: measured vs Ritz model": report.mac_ritz,
        "auto-MAC of the measured shapes": report.auto_mac,
    }
    assert set(panels) == set(matrices)
    for title, matrix in matrices.items():
        ax = panels[title]
        written = {(round(t.get_position()[1]), round(t.get_position()[0])): t.get_text() for t in ax.texts}
        assert len(written) == matrix.size, f"{title}: not every cell has its number"
        for (i, j), value in np.ndenumerate(matrix):
            assert written[i, j] == f"{value:.2f}", (title, i, j)
        assert ax.get_ylabel() == "measured mode"
        assert "mode" in ax.get_xlabel()
    assert panels["MAC: measured vs exact beam"].get_xlabel() == "beam mode (exact)"


def test_measured_shapes_are_turned_to_the_exact_sign_with_their_uncertainty(drawn):
    report, _, _, figures = drawn
    (fig,) = [f for f in figures if "mode shapes" in f.get_suptitle()]
    shape_axes = [ax for ax in fig.axes if ax.get_title(loc="left").startswith("mode ")]
    assert len(shape_axes) == 3
    for k, ax in enumerate(shape_axes):
        measured = [c for c in ax.containers if c.get_label().startswith("measured")]
        (bars,) = measured
        y = bars.lines[0].get_ydata()
        expected = np.real(report.shapes[k]) * (-1 if k == 1 else 1)
        np.testing.assert_allclose(y, expected)
        assert "standard uncertainty" in bars.get_label()
        assert ("flipped" in ax.get_title(loc="left")) == (k == 1)
        assert {line.get_label() for line in ax.lines} >= {"exact beam", "Ritz"}


def test_a_point_name_with_dollars_is_drawn_literally():
    report = _report(point_names=np.array(["$x^", "p2", "p3", "$\\frac$", "p5", "p6", "tip"]))
    page, pngs = render_modal_test_report(report)  # mathtext would raise on these
    assert "$\\frac$" in html.unescape(page)
    assert all(png.startswith(PNG_SIGNATURE) for png in pngs.values())


def test_stability_given_as_arrays_draws_the_same_and_a_bad_status_is_one_line(drawn):
    rows = drawn[0].stability
    as_arrays = {
        "order": np.array([o for o, _, _ in rows]),
        "frequency_hz": np.array([f for _, f, _ in rows]),
        "status": np.array([s for _, _, s in rows]),
    }
    assert mtr.stability_figure(_report(stability=as_arrays)) == drawn[2]["stability"]
    with pytest.raises(ValueError, match="stability status 'maybe'"):
        render_modal_test_report(_report(stability=[*rows, (4, 50.0, "maybe")]))


def test_arrays_that_disagree_are_refused_by_name():
    good = _report()
    with pytest.raises(ValueError, match=r"shape_std has shape \(3, 6\), expected 3x7"):
        render_modal_test_report(dataclasses.replace(good, shape_std=good.shape_std[:, :6]))
    with pytest.raises(ValueError, match="synthesized_frf"):
        render_modal_test_report(dataclasses.replace(good, synthesized_frf=good.synthesized_frf[:, :-1]))

"""The report behind `daq model`: computed with analysis/, rendered with rich or as JSON."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from rich.console import Console
from rich.table import Table

from analysis.beam import BeamProperties, SectionSource
from analysis.table2 import DampingSummary, Table2, damping_summary, table2

#: Above this ratio a bare aluminium cantilever is implausible (typical: 0.1-1 %).
PLAUSIBLE_DAMPING_RATIO = 0.02


def _finite_or_none(value: float) -> float | None:
    return None if not math.isfinite(value) else float(value)


def build_report(
    beam: BeamProperties, n_functions: int, section: SectionSource, damping: np.ndarray, damping_source: str
) -> tuple[Table2, DampingSummary, dict[str, Any]]:
    """Compute both parts and a JSON-ready dict of them."""
    t2 = table2(beam, n_functions, section)
    ds = damping_summary(damping, beam, section)
    rows = []
    for k in range(t2.n_rows):
        row: dict[str, Any] = {"mode": k + 1}
        for name, column in (
            ("ritz_hz", t2.ritz_hz),
            ("exact_tabulated_hz", t2.exact_tabulated_hz),
            ("exact_derived_hz", t2.exact_derived_hz),
            ("seed_analytical_hz", t2.seed_analytical_hz),
            ("seed_experimental_hz", t2.seed_experimental_hz),
        ):
            row[name] = _finite_or_none(column[k])
            if name != "seed_experimental_hz":
                row[name.removesuffix("_hz") + "_diff_pct"] = _finite_or_none(t2.difference_pct(column)[k])
        rows.append(row)
    modes = ds.modes
    report = {
        "beam": beam.to_dict(),
        "table2": {"n_functions": n_functions, "section": section, "rows": rows},
        "damping": {
            "source": damping_source,
            "n_functions": int(ds.damping.shape[0]),
            "matrix_n_s_per_m": ds.damping.tolist(),
            "symmetric_part_eigenvalues": ds.symmetric_eigenvalues.tolist(),
            "definiteness": ds.definiteness,
            "positive_definite": ds.positive_definite,
            "symmetric": ds.symmetric,
            "n_real_poles": int(modes.n_real_poles),
            "n_unstable_poles": int(modes.n_unstable_poles),
            "modes": [
                {
                    "mode": k + 1,
                    "natural_frequency_hz": _finite_or_none(modes.natural_frequencies_hz[k]),
                    "damped_frequency_hz": _finite_or_none(modes.damped_frequencies_hz[k]),
                    "damping_ratio": _finite_or_none(modes.damping_ratios[k]),
                }
                for k in range(ds.damping.shape[0])
                if math.isfinite(modes.natural_frequencies_hz[k])
            ],
        },
    }
    return t2, ds, report


def _fmt(value: float, digits: int = 5) -> str:
    # + 0.0 turns -0.0 into 0.0: an undamped mode should not print as "-0.000000".
    return "—" if not math.isfinite(value) else f"{round(value, digits) + 0.0:.{digits}f}"


def _pct(value: float) -> str:
    return "—" if not math.isfinite(value) else f"{value:+.4f}"


def render(console: Console, beam: BeamProperties, t2: Table2, ds: DampingSummary, source: str) -> None:
    derived = beam.with_section("derived")
    console.print(
        f"[bold]Cantilever[/] L = {beam.length_m} m, b x h = {beam.width_m * 1e3:g} x "
        f"{beam.height_m * 1e3:g} mm, rho = {beam.density_kg_m3:g} kg/m³, E = {beam.youngs_modulus_pa:.4g} Pa"
    )
    console.print(f"  tabulated: A = {beam.area_m2:.4e} m², I = {beam.second_moment_m4:.4e} m⁴")
    console.print(
        f"  derived:   A = b·h = {derived.area_m2:.4e} m², I = b·h³/12 = {derived.second_moment_m4:.4e} m⁴"
    )
    console.print()
    freq = Table(title="Natural frequencies (Hz), the seed's Table 2 redone", title_justify="left")
    freq.add_column("Mode", justify="right")
    freq.add_column(f"Ritz N={t2.n_functions}\n{t2.section}", justify="right")
    freq.add_column("Exact beam\ntabulated", justify="right")
    freq.add_column("Exact beam\nderived", justify="right")
    freq.add_column("Seed\nanalytical", justify="right")
    freq.add_column("Seed\nexperimental", justify="right")
    diff = Table(title="Difference from the seed's experimental column (%)", title_justify="left")
    diff.add_column("Mode", justify="right")
    for label in ("Ritz", "Exact tabulated", "Exact derived", "Seed analytical"):
        diff.add_column(label, justify="right")
    columns = (t2.ritz_hz, t2.exact_tabulated_hz, t2.exact_derived_hz, t2.seed_analytical_hz)
    for k in range(t2.n_rows):
        freq.add_row(str(k + 1), *(_fmt(c[k]) for c in (*columns, t2.seed_experimental_hz)))
        if math.isfinite(t2.seed_experimental_hz[k]):
            diff.add_row(str(k + 1), *(_pct(t2.difference_pct(c)[k]) for c in columns))
    console.print(freq)
    console.print(diff)
    console.print(
        "tabulated: A and I as in Table 1; derived: A = b·h, I = b·h³/12. The seed's analytical "
        "column cannot be reproduced from its own eqs (10)-(11) and Table 1; its experimental "
        "column matches the exact beam."
    )
    console.print()

    n = ds.damping.shape[0]
    modes = ds.modes
    damp = Table(title=f"Damped Ritz model N={n}, damping matrix: {source}", title_justify="left")
    damp.add_column("Mode", justify="right")
    damp.add_column("|λ|/2π (Hz)", justify="right")
    damp.add_column("Im λ/2π (Hz)", justify="right")
    damp.add_column("Damping ratio", justify="right")
    for k in range(n):
        if math.isfinite(modes.natural_frequencies_hz[k]):
            damp.add_row(
                str(k + 1),
                _fmt(modes.natural_frequencies_hz[k]),
                _fmt(modes.damped_frequencies_hz[k]),
                _fmt(modes.damping_ratios[k], 6),
            )
    console.print(damp)
    eig = ", ".join(f"{v:.4g}" for v in ds.symmetric_eigenvalues + 0.0)
    meaning = {
        "positive definite": "every mode is damped",
        "positive semi-definite": "some motion is undamped",
        "indefinite": "the model can gain energy",
    }[ds.definiteness]
    console.print(f"Eigenvalues of R (symmetric part): {eig} ({ds.definiteness}: {meaning})")
    if not ds.symmetric:
        console.print("R is not symmetric: its antisymmetric part acts as a gyroscopic, not a damping, term.")
    if int(modes.n_real_poles):
        console.print(f"{int(modes.n_real_poles)} real (non-oscillating) poles are not listed as modes.")
    if int(modes.n_unstable_poles):
        console.print(f"[red]{int(modes.n_unstable_poles)} poles have a positive real part: unstable.[/]")
    ratios = modes.damping_ratios[np.isfinite(modes.damping_ratios)]
    if ratios.size and ratios.max() > PLAUSIBLE_DAMPING_RATIO:
        console.print(
            f"[yellow]Note:[/] damping ratios up to {100 * ratios.max():.1f} % are far above the "
            "0.1-1 % typical of a bare aluminium cantilever."
        )

"""The fit's words where the report and the refusals say them: the report's stiffness
line as the terminal prints it, and what a run with no test article is."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from daq.report.page import _stiffness_text
from daq.workflows.fit import fitted_beam


def _run(kind: str, replayed_from: dict | None = None) -> SimpleNamespace:
    provenance = {} if replayed_from is None else {"replayed_from": replayed_from}
    return SimpleNamespace(sample=None, kind=kind, provenance=provenance)


@pytest.mark.parametrize(
    ("run", "said"),
    [
        (_run("imported"), "(an imported file)"),
        (_run("replayed", {"run_id": "x", "kind": "imported"}), "(a replay of an imported file)"),
    ],
)
def test_a_run_without_test_article_is_named_for_what_it_is(run, said):
    with pytest.raises(ValueError, match="no beam model") as caught:
        fitted_beam(run, None)
    assert said in str(caught.value)


def test_the_reports_stiffness_line_reads_like_the_terminals():
    modes = {"update": "scale on E, then each mode's frequency", "scale": 0.984431,
             "mode_frequencies": {"applied": True}}  # fmt: skip
    assert _stiffness_text({"stiffness": modes}) == (
        "stiffness scaled by 0.98443 to the run's frequencies, then each mode at its identified frequency"
    )
    why = "an identified mode has 20.2 % damping"
    kept = {"update": "scale on E", "scale": 0.99898, "mode_frequencies": {"applied": False, "reason": why}}
    assert _stiffness_text({"stiffness": kept}) == (
        f"stiffness scaled by 0.99898 to the run's frequencies (modes kept: {why})"
    )
    assert _stiffness_text({"stiffness": {"update": "none"}}) == "stiffness as built (--stiffness none)"

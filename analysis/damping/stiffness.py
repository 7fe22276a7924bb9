"""One-parameter stiffness update from identified natural frequencies.

The Ritz model's frequencies miss the measured ones by a few percent (the seed's
Table 2), and a damping fit against a model whose modes sit at the wrong
frequencies must distort R to move the poles. A single scale s on K (a scale on
E I) moves every undamped frequency by the same factor sqrt(s), without changing
the mode shapes; it is the one stiffness correction a driving-point
measurement supports without further assumptions.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from analysis.damping.modal_estimate import match_modes, undamped_modes
from analysis.structure import StructuralModel

#: Largest relative frequency miss for an identified mode to count as a model mode's partner.
MATCH_TOLERANCE = 0.2


def _paired(
    model: StructuralModel, identified_hz: np.ndarray, tolerance: float
) -> tuple[np.ndarray, np.ndarray]:
    """Model frequencies (N,) Hz and the identified partner of each (N,), NaN where none."""
    omega, _ = undamped_modes(model)
    model_hz = omega / (2.0 * np.pi)
    f_id = np.asarray(identified_hz, dtype=float)
    partner = np.full(model_hz.size, np.nan)
    match = match_modes(f_id, model_hz)
    for i, r in enumerate(match):
        if r >= 0 and abs(f_id[i] / model_hz[r] - 1.0) <= tolerance:
            partner[r] = f_id[i]
    return model_hz, partner


def frequency_errors(
    model: StructuralModel, identified_hz: np.ndarray, tolerance: float = MATCH_TOLERANCE
) -> np.ndarray:
    """Per model mode, 100 (f_model - f_identified) / f_identified, %; NaN where no partner.

    Model modes are the undamped modes of (M, K), Hz; identified modes pair with
    them by nearest frequency, each once, within ``tolerance`` (relative).
    """
    model_hz, partner = _paired(model, identified_hz, tolerance)
    return 100.0 * (model_hz - partner) / partner


def update_stiffness(
    model: StructuralModel, identified_frequency_hz: np.ndarray, tolerance: float = MATCH_TOLERANCE
) -> tuple[StructuralModel, float, dict[str, Any]]:
    """Scale K by the s that best fits the identified frequencies.

    The model's undamped frequencies f_r become sqrt(s) f_r. s minimises the
    summed squared relative misses sum_r (1 - sqrt(s) f_r / f_id,r)^2 over the
    paired modes (relative, so the highest mode does not dominate), which has
    the closed form sqrt(s) = sum(f_r / f_id,r) / sum((f_r / f_id,r)^2).

    Parameters
    ----------
    model : the model to update; M, force and sensor vectors are kept.
    identified_frequency_hz : (m,) Hz. Each model mode takes the identified mode
        nearest in frequency (each once) if within ``tolerance`` (relative).

    Returns
    -------
    model_updated : the model with stiffness s K.
    scale : s (dimensionless). If the data come from a beam whose E is
        c times the model's, s = c.
    info : {"model_hz": (N,) before, "updated_hz": (N,) after, "identified_hz":
        (N,) partner per model mode (NaN: none), "error_before_pct",
        "error_after_pct": (N,) as ``frequency_errors``, "n_used": int}.
    """
    model_hz, partner = _paired(model, identified_frequency_hz, tolerance)
    used = np.isfinite(partner)
    if not np.any(used):
        raise ValueError("no identified frequency lies within the tolerance of a model frequency")
    ratio = model_hz[used] / partner[used]
    root = float(np.sum(ratio) / np.sum(ratio**2))
    scale = root**2
    updated = dataclasses.replace(model, stiffness=scale * model.stiffness)
    updated_hz = root * model_hz
    info = {
        "model_hz": model_hz,
        "updated_hz": updated_hz,
        "identified_hz": partner,
        "error_before_pct": 100.0 * (model_hz - partner) / partner,
        "error_after_pct": 100.0 * (updated_hz - partner) / partner,
        "n_used": int(np.count_nonzero(used)),
    }
    return updated, scale, info


#: Largest identified damping ratio at which each mode's frequency is taken as its
#: undamped frequency (``update_mode_frequencies``).
LIGHT_DAMPING = 0.05


def update_mode_frequencies(
    model: StructuralModel,
    identified_frequency_hz: np.ndarray,
    identified_damping_ratio: np.ndarray,
    tolerance: float = MATCH_TOLERANCE,
    light: float = LIGHT_DAMPING,
) -> tuple[StructuralModel, dict[str, Any]]:
    """Give each model mode its identified partner's frequency, mode shapes kept.

    K becomes M Phi diag(omega_r^2) Phi^T M (Phi the mass-normalised undamped modes
    of ``model``, omega_r the identified frequency of mode r's partner, the model's
    own where there is none), so every paired undamped frequency equals the
    identified one exactly. One factor on E (``update_stiffness``) leaves misses of
    up to ~1 % on a Ritz model, more than a lightly damped mode's half-power
    bandwidth (2 zeta): a damping fit then bends R (large, indefinite coupling
    terms) to move the poles, since that is all it can move.

    Only under light damping: a damped pole |lambda_r| sits within about zeta^2 of
    the undamped frequency whatever R couples, but heavy non-proportional damping
    moves it by percents (eq (18) moves the seed beam's second mode 2.5 %), which
    must stay R's to explain. With any identified ratio at or above ``light`` the
    model is returned unchanged.

    Returns
    -------
    model_updated, info : {"applied": bool, "reason": str, "before_hz": (N,),
        "after_hz": (N,), "identified_hz": (N,) partner per model mode (NaN: none)}.
    """
    zeta = np.asarray(identified_damping_ratio, dtype=float)
    _, phi = undamped_modes(model)
    model_hz, partner = _paired(model, identified_frequency_hz, tolerance)
    info: dict[str, Any] = {"before_hz": model_hz, "after_hz": model_hz, "identified_hz": partner}
    if zeta.size and float(np.nanmax(zeta)) >= light:
        reason = (
            f"an identified mode has {100 * float(np.nanmax(zeta)):.3g} % damping (>= {100 * light:g} %): "
            "its pole need not sit at the undamped frequency"
        )
        return model, {**info, "applied": False, "reason": reason}
    used = np.isfinite(partner)
    if not np.any(used):
        return model, {**info, "applied": False, "reason": "no identified mode pairs with a model mode"}
    target = np.where(used, partner, model_hz)
    m_phi = model.mass @ phi
    stiffness = (m_phi * (2.0 * np.pi * target) ** 2) @ m_phi.T
    updated = dataclasses.replace(model, stiffness=0.5 * (stiffness + stiffness.T))
    reason = f"{int(used.sum())} model modes set to the identified frequencies"
    return updated, {**info, "after_hz": target, "applied": True, "reason": reason}

"""Modal identification of measured FRFs: automatic LSCF + stability + LSFD, and the
half-power / circle-fit baseline. Pure numerics (numpy, scipy)."""

from analysis.modal_id.circle_fit import CircleFit, circle_fit
from analysis.modal_id.identify import (
    DENOMINATOR,
    NORMALISATIONS,
    ModalResult,
    Mode,
    ModeQuality,
    StabilityDiagram,
    identify_modes,
)
from analysis.modal_id.lscf import LscfPoles, lscf_poles
from analysis.modal_id.lsfd import LsfdResult, lsfd
from analysis.modal_id.peaks import peak_pick
from analysis.modal_id.stability import classify_order, cluster_poles, pick_clusters, stability_diagram

__all__ = [
    "DENOMINATOR",
    "NORMALISATIONS",
    "CircleFit",
    "LscfPoles",
    "LsfdResult",
    "ModalResult",
    "Mode",
    "ModeQuality",
    "StabilityDiagram",
    "circle_fit",
    "classify_order",
    "cluster_poles",
    "identify_modes",
    "lscf_poles",
    "lsfd",
    "peak_pick",
    "pick_clusters",
    "stability_diagram",
]

"""Where the simulated analyzer's hits come from: physics, or a recorded run (replay)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from sims.acquisition import ChannelChains, NoiseModel, Record, acquire, channel_chains
from sims.hammer import HammerModel, draw_hit
from sims.models import DEFAULT_MODEL, Model, get_model
from sims.pole_residue import PoleResidueSystem
from sims.scenarios import Specimen, build_specimen
from sims.settings import RECORD_SAMPLES, SAMPLE_RATE_PER_SPAN, AnalyzerSettings

#: Samples of a 35660A zoom record: complex, half as many as a baseband record.
ZOOM_RECORD_SAMPLES = RECORD_SAMPLES // 2

#: A technician who sees no trigger hits again; after this many misses the
#: analyzer waits for ever (the driver's trigger timeout takes over).
MAX_MISSED_HITS = 20


class SourceError(Exception):
    """The source cannot serve a hit with these settings (reported as an instrument error)."""


@dataclass(frozen=True)
class TimedRecord:
    """A record and how long after arming its trigger came, physics seconds."""

    record: Record
    trigger_after_s: float


class PhysicsSource:
    """Hits on a specimen from the beam model, with a random hammer and sensor noise.

    specimen : a Specimen, or a scenario's name (``sims.scenarios``: seed, realistic,
        custom) built with the positions and damping given here.
    force_at_m, sensor_at_m : hammer and accelerometer, m from the clamp (0 < x <= L;
        None: the tip). Only with a scenario's name; ``move`` changes them later.
    damping : (3, 3) N s/m, a symmetric positive semi-definite damping matrix of your
        own on the seed's Ritz beam (scenario ``custom``). Only with a scenario's name.
    """

    def __init__(
        self,
        specimen: Specimen | str = "seed",
        hammer: HammerModel | None = None,
        noise: NoiseModel | None = None,
        seed: int = 0,
        force_at_m: float | None = None,
        sensor_at_m: float | None = None,
        damping: np.ndarray | None = None,
    ) -> None:
        if isinstance(specimen, str):
            specimen = build_specimen(specimen, force_at_m, sensor_at_m, damping=damping)
        elif force_at_m is not None or sensor_at_m is not None or damping is not None:
            raise ValueError("positions and damping go with a scenario's name, not a built Specimen")
        self.hammer = hammer or HammerModel()
        self.noise = noise or NoiseModel()
        self.reseed(seed)
        self._cache: dict[tuple, ChannelChains] = {}
        self.use(specimen)
        self.hits_drawn = 0

    def use(self, specimen: Specimen) -> None:
        """Strike ``specimen`` from the next hit drawn on (the random stream goes on)."""
        self.specimen = specimen
        self._accel: PoleResidueSystem = specimen.acceleration_system()
        self._cache.clear()

    def move(self, force_at_m: float | None = None, sensor_at_m: float | None = None) -> None:
        """Put the hammer and/or the accelerometer elsewhere, m from the clamp (None keeps
        one where it is); the next hit drawn is struck and measured there. ValueError
        (nothing changes) for a position off the beam."""
        self.use(self.specimen.moved(force_at_m, sensor_at_m))

    def reseed(self, seed: int) -> None:
        self.seed = int(seed)
        self.rng = np.random.default_rng(self.seed)

    def set_noise(self, enabled: bool) -> None:
        self.noise = replace(self.noise, enabled=enabled)

    def _chains(self, settings: AnalyzerSettings) -> ChannelChains:
        key = (
            settings.span_hz,
            settings.center_hz,
            settings.sensitivity1_v_per_eu,
            settings.sensitivity2_v_per_eu,
            settings.ac_coupled1,
            settings.ac_coupled2,
        )
        if key not in self._cache:
            self._cache.clear()
            self._cache[key] = channel_chains(self._accel, settings)
        return self._cache[key]

    def next_record(self, settings: AnalyzerSettings) -> TimedRecord | None:
        """The next hit that triggers, or None if the technician gives up."""
        chains = self._chains(settings)
        waited = 0.0
        pre_trigger = max(0.0, -settings.trigger_delay_s)
        for _ in range(MAX_MISSED_HITS):
            hit = draw_hit(self.hammer, self.rng, earliest_s=pre_trigger + 0.01)
            self.hits_drawn += 1
            record = acquire(hit, chains, settings, self.noise, self.rng)
            if record is not None:
                if settings.trigger_source == "FREE":
                    return TimedRecord(record, waited)
                # The crossing comes within the contact; its start is close enough
                # for the analyzer's status timing.
                return TimedRecord(record, waited + hit.start_s)
            waited += hit.start_s + settings.record_length_s
        return None


@dataclass
class RecordedHit:
    """One hit of a recorded run: the two channels in engineering units.

    force_n, acceleration_m_s2 : (n,) float64 at baseband, or (n/2,) complex128 for
        a zoom record (the band mixed down by ``center_hz``), N and m/s^2; n = 2.56 x
        lines, 1024 on the 35660A, 2048 on the 3562A.
    sample_rate_hz : Hz (2.56 x span at baseband, 1.28 x span in zoom).
    start_s : time of the first sample after the trigger, s.
    center_hz : 0 at baseband, the zoom centre frequency otherwise, Hz.
    """

    force_n: np.ndarray
    acceleration_m_s2: np.ndarray
    sample_rate_hz: float
    start_s: float = 0.0
    overload: tuple[bool, bool] = (False, False)
    center_hz: float = 0.0

    @property
    def zoom(self) -> bool:
        return bool(np.iscomplexobj(self.force_n))


@dataclass
class ReplaySource:
    """Serves recorded hits in order, bit for bit, instead of physics.

    ``model`` is the instrument the hits are served to: each hit must hold a record
    length that model can take (2.56 x one of its line counts real samples, or half
    as many complex ones), otherwise ValueError at once: a 1024-sample run cannot be
    replayed into a 3562A (2048 samples). The analyzer must then be set to the
    recording's span (sample rate) and, on a model with a choice of lines, to the
    lines that give the recording's length: otherwise it reports an error when it
    arms. ``loop`` starts over after the last hit, otherwise the hammer falls silent.
    """

    hits: Sequence[RecordedHit]
    loop: bool = False
    position: int = field(default=0)
    model: Model | str = DEFAULT_MODEL

    def __post_init__(self) -> None:
        self.model = get_model(self.model)
        lengths = self.model.record_samples_offered
        for i, hit in enumerate(self.hits):
            n = hit.force_n.shape[0] if hit.force_n.ndim == 1 else -1
            kind = "complex (zoom)" if hit.zoom else "real"
            offered = tuple(x // 2 for x in lengths) if hit.zoom else lengths
            wanted = "/".join(str(x) for x in offered)
            if n not in offered or hit.acceleration_m_s2.shape != (n,):
                raise ValueError(
                    f"recorded hit {i} does not hold two {wanted}-sample {kind} channels "
                    f"(the {self.model.name} records {wanted})"
                )
            if np.iscomplexobj(hit.acceleration_m_s2) != hit.zoom:
                raise ValueError(f"recorded hit {i} mixes a real and a complex channel")
            if hit.zoom != (hit.center_hz > 0):
                raise ValueError(f"recorded hit {i}: a zoom record needs center_hz > 0, baseband 0")

    def next_record(self, settings: AnalyzerSettings) -> TimedRecord | None:
        if self.position >= len(self.hits):
            if not self.loop or not self.hits:
                return None
            self.position = 0
        hit = self.hits[self.position]
        if hit.zoom:
            if not (settings.zoom and math.isclose(hit.center_hz, settings.center_hz, rel_tol=1e-12)):
                raise SourceError(f"replay of a zoom record: set CF to its center, {hit.center_hz:g} Hz")
        elif settings.zoom:
            raise SourceError("replay serves baseband records: set CF to span/2")
        if hit.force_n.size != settings.record_points:
            lines = round(hit.force_n.size * (2 if hit.zoom else 1) / SAMPLE_RATE_PER_SPAN)
            raise SourceError(
                f"replay holds {hit.force_n.size}-sample records, the analyzer records "
                f"{settings.record_points}: set {lines} lines"
            )
        if not math.isclose(hit.sample_rate_hz, settings.sample_rate_hz, rel_tol=1e-9):
            per_span = SAMPLE_RATE_PER_SPAN / (2 if hit.zoom else 1)
            raise SourceError(
                f"replay recorded at {hit.sample_rate_hz:g} Hz sampling (span "
                f"{hit.sample_rate_hz / per_span:g} Hz); set FRS to match"
            )
        self.position += 1
        dtype = complex if hit.zoom else float
        record = Record(
            force_n=np.array(hit.force_n, dtype=dtype),
            acceleration_m_s2=np.array(hit.acceleration_m_s2, dtype=dtype),
            start_s=hit.start_s,
            sample_rate_hz=hit.sample_rate_hz,
            overload=hit.overload,
            peak_v=(math.nan, math.nan),
        )
        return TimedRecord(record, 0.5)

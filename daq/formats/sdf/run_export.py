"""A run as an SDF revision 3 file (`daq export RUN --format sdf`); docs/sdf.md.

Two channel headers: 0 force (N, reference), 1 response (m/s^2), both with
int2engrUnit 1 and window corrections of 1, so stored values are the run's values.
Data headers, in this order:

- "Time": the hits, one scan per hit (a scan structure of n_hits scans, depth order),
  two traces per scan (force, response), float64 (complex for zoom records), x linear
  from the pre-trigger start in steps of 1 / sample rate;
- "Analyzer FRF", "Imported FRF": the analyzer's and the measured FRFs, complex float64,
  response over force (powers +1, -1); x linear when first + k * step rebuilds the
  frequencies bit for bit, else float64 values in XDATA;
- "Analyzer Coh", "Imported Coh": their coherence, when known;
- the run's spectra, one data header each, titled by its label (cut to SDF's 16
  characters), of the data type of its kind (spectra.py DATA_TYPES), float64 or complex
  float64 as stored, with no channel (-1) and the unit as a valid yUnit, so that the
  values read back are the stored ones.

A COMMENT record carries what SDF has no field for (daq/formats/sdf/notes.py), among
it each spectrum's full label and unit. The file
is read back with our reader before it replaces the target: every value must come back
bit for bit, else FormatError and the target is untouched.
"""

from __future__ import annotations

from datetime import datetime
from pathlib import Path

import numpy as np

from daq import __version__
from daq.formats.errors import FormatError
from daq.formats.imported import atomic_temp, commit_temp, discard_temp, one_line, show_path
from daq.formats.sdf import codes
from daq.formats.sdf.axes import linear_axis
from daq.formats.sdf.model import (
    COUNT,
    HERTZ,
    METRE_PER_S2,
    NEWTON,
    SECOND,
    Channel,
    Comment,
    DataHeader,
    FileHeader,
    MeasHeader,
    Scans,
    ScanVariable,
    SdfFile,
    Vector,
    Window,
)
from daq.formats.sdf.notes import Notes, encode_notes
from daq.formats.sdf.reader import parse_sdf
from daq.formats.sdf.spectra import DATA_TYPES, unit_of
from daq.formats.sdf.writer import encode_sdf
from daq.store.model import Hits, MeasuredFrf, Run, Spectra

FORCE, RESPONSE = 0, 1
Z_DIRECTION = 3


def write_sdf_run(run: Run, path: Path | str) -> None:
    """Write ``run`` to ``path`` as SDF revision 3, atomically, checked by reading it back."""
    path = Path(path)
    name = show_path(path)
    sdf = sdf_of_run(run)
    for dh in sdf.data:
        if not (np.all(np.isfinite(dh.y)) and np.all(np.isfinite(dh.x))):
            raise FormatError(f"cannot write {name}: run {run.run_id} holds non-finite values")
    try:
        data = encode_sdf(sdf, revision=3)
    except ValueError as exc:
        raise FormatError(f"cannot write {name}: {one_line(str(exc))}") from None
    back = parse_sdf(data, name)
    for wrote, read in zip(sdf.data, back.data, strict=True):
        if not (_same(wrote.y, read.y) and _same(np.asarray(wrote.x, dtype=np.float64), read.x)):
            raise FormatError(f"cannot write {name} exactly: {wrote.title!r} reads back different values")
    temp = atomic_temp(path)
    try:
        try:
            temp.write_bytes(data)
        except OSError as exc:
            raise FormatError(f"cannot write {name}: {exc.strerror or exc}") from None
        commit_temp(temp, path)
    except BaseException:
        discard_temp(temp)
        raise


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


def sdf_of_run(run: Run) -> SdfFile:
    """The SdfFile `daq export --format sdf` writes for ``run`` (module docstring)."""
    decay, pulse = _exp_window(run)
    notes = Notes(run_id=run.run_id)
    data: list[DataHeader] = []
    scans = None
    hits = run.hits
    if hits is not None:
        data.append(_time_header(hits))
        numbers = np.arange(hits.n_hits, dtype=np.float64)
        scans = Scans(hits.n_hits, hits.n_hits - 1, codes.DEPTH, [ScanVariable(numbers, codes.INT32, COUNT)])
        notes.keys.update(
            sample_rate_hz=repr(float(hits.sample_rate_hz)),
            start_s=repr(float(hits.start_s)),
            center_hz=repr(float(hits.center_hz)),
        )
        notes.rejected = {k: str(hits.reject_reason[k]) for k in range(hits.n_hits) if not hits.accepted[k]}
    sets = [
        (tag, f) for tag, f in (("Analyzer", run.analyzer), ("Imported", run.measured_frfs)) if f is not None
    ]
    for tag, frfs in sets:
        if frfs.form != "accelerance":
            # The SDF writer labels every FRF (m/s^2)/N; a receptance must not pass as one.
            raise FormatError(
                f"run {run.run_id} holds FRFs of {frfs.form}; SDF export writes accelerance only: "
                "use --format uff"
            )
        data.append(_frf_header(f"{tag} FRF", frfs, frfs.frf, codes.FREQ_RESP_DATA))
    for tag, frfs in sets:
        if frfs.coherence is not None:
            data.append(_frf_header(f"{tag} Coh", frfs, frfs.coherence, codes.ORD_COH_DATA))
    notes.labels = dict(enumerate(label for _tag, frfs in sets for label in frfs.labels))
    if run.spectra is not None:
        data += [_spectrum_header(run.spectra, k) for k in range(run.spectra.n_traces)]
        notes.spectrum_labels = dict(enumerate(run.spectra.labels))
        notes.spectrum_units = dict(enumerate(run.spectra.units))
    if decay is not None:
        notes.keys.update(exp_decay_s=repr(decay), pulse_s=repr(pulse))
    return SdfFile(
        file=_file_header(run),
        meas=_meas_header(run, sets),
        data=data,
        channels=_channels(run, decay),
        scans=scans,
        comments=[Comment(encode_notes(notes))],
    )


def _file_header(run: Run) -> FileHeader:
    start = datetime.fromisoformat(run.start_time)
    return FileHeader(
        revision=3,
        applic=codes.UNKNOWN_APPLIC,
        year=start.year,
        month_day=start.month * 100 + start.day,
        hour_min=start.hour * 100 + start.minute,
        applic_version=__version__[:7],
    )


def _meas_header(run: Run, sets: list[tuple[str, MeasuredFrf]]) -> MeasHeader:
    hits = run.hits
    # Frequency lines: the FRFs', else those an FFT analyzer shows for these records (block / 2.56).
    spectra = [run.spectra] if run.spectra is not None else []
    n_lines = max(
        [f.n_lines for _tag, f in sets] + [s.n_lines for s in spectra],
        default=int(hits.n_samples / 2.56) + 1 if hits else 1,
    )
    if hits is not None:
        span = hits.sample_rate_hz / (1.28 if hits.is_zoom else 2.56)
        center = hits.center_hz if hits.is_zoom else span / 2
        block = hits.n_samples
    else:
        freq = sets[0][1].frequency_hz if sets else spectra[0].frequency_hz
        span, center, block = (
            float(freq[-1] - freq[0]),
            float(freq[-1] + freq[0]) / 2,
            2 * max(1, n_lines - 1),
        )
    return MeasHeader(
        center_freq=float(center),
        span_freq=float(span),
        block_size=block,
        zoom=int(hits is not None and hits.is_zoom),
        start_freq_index=0,
        stop_freq_index=n_lines - 1,
        average_type=codes.AVERAGE_OFF,
        average_num=int(np.count_nonzero(hits.accepted)) if hits is not None else 1,
        title=f"cantilever-daq run {run.run_id}",
        meas_type=codes.FFT_MEAS,
        detection=codes.SAMPLE_DETECT,
    )


def _exp_window(run: Run) -> tuple[float | None, float]:
    """(exp_decay_s, pulse_s) of the exponential window the run's FRFs went through, as
    the UFF export finds them: the analyzer's accelerometer setup, else an imported file's."""
    if run.analyzer is not None and run.instrument is not None:
        setup = run.instrument.settings.get("accelerometer", {})
        if isinstance(setup, dict) and setup.get("window") == "EXPO" and setup.get("exp_decay_s"):
            pulse = max(0.0, -run.hits.start_s) if run.hits is not None else 0.0
            return float(setup["exp_decay_s"]), pulse
    source = run.provenance.get("imported_from", {})
    if run.measured_frfs is not None and isinstance(source, dict) and source.get("exp_decay_s"):
        return float(source["exp_decay_s"]), float(source.get("pulse_s") or 0.0)
    return None, 0.0


def _channels(run: Run, decay: float | None) -> list[Channel]:
    overload = run.hits.overload.any(axis=0) if run.hits is not None else np.zeros(2, dtype=bool)
    force_window = Window(type=codes.UNIFORM_WINDOW)
    if run.instrument is not None:
        setup = run.instrument.settings.get("hammer", {})
        if isinstance(setup, dict) and setup.get("window") == "FORC":
            force_window = Window(type=codes.FORCE_WINDOW, trunc=float(setup.get("force_width_s") or 0.0))
    response_window = Window(type=codes.UNIFORM_WINDOW)
    if decay is not None:
        response_window = Window(type=codes.EXPONENTIAL_WINDOW, time_const=decay)
    common = {"module_id": "cantilever-daq", "direction": Z_DIRECTION, "int2engr": 1.0}
    return [
        Channel(label="Force", window=force_window, int_label="N", eng_unit=NEWTON, point_num=1,
                overloaded=int(overload[0]), attribute=codes.REFERENCE_ATTRIB, channel_number=0, **common),
        Channel(label="Response", window=response_window, int_label="m/s^2", eng_unit=METRE_PER_S2,
                point_num=2, overloaded=int(overload[1]), channel_number=1, **common),
    ]  # fmt: skip


def _time_header(hits: Hits) -> DataHeader:
    n = hits.n_samples
    return DataHeader(
        title="Time",
        domain=codes.TIME_DOMAIN,
        data_type=codes.TIME_DATA,
        n_points=n,
        last_valid_index=n - 1,
        x_resolution=codes.LINEAR_RES,
        xdata_type=codes.FLOAT64,
        ydata_type=codes.FLOAT64,
        y_is_complex=int(hits.is_zoom),
        total_rows=2,
        x_unit=SECOND,
        first_x=float(hits.start_s),
        delta_x=1.0 / float(hits.sample_rate_hz),
        scan_data=1,
        window_applied=0,
        vectors=[Vector(FORCE, -1, 48, 0), Vector(RESPONSE, -1, 48, 0)],
        x=linear_axis(hits.start_s, 1.0 / float(hits.sample_rate_hz), n),
        y=np.stack([hits.force_n, hits.response_m_s2], axis=1),
    )


def _frf_header(title: str, frfs: MeasuredFrf, values: np.ndarray, data_type: int) -> DataHeader:
    freq = frfs.frequency_hz
    n = freq.size
    step = float(freq[1] - freq[0]) if n > 1 else 0.0
    linear = _same(linear_axis(freq[0], step, n), freq)
    is_frf = data_type == codes.FREQ_RESP_DATA
    powers = (48, -48) if is_frf else (0, 0)
    return DataHeader(
        title=title,
        domain=codes.FREQ_DOMAIN,
        data_type=data_type,
        n_points=n,
        last_valid_index=n - 1,
        x_resolution=codes.LINEAR_RES if linear else codes.ARB_PER_DATA_HDR,
        xdata_type=codes.FLOAT64,
        ydata_type=codes.FLOAT64,
        y_is_complex=int(is_frf),
        y_is_normalized=int(not is_frf),
        y_is_power=int(not is_frf),
        total_rows=frfs.n_frf,
        x_unit=HERTZ,
        first_x=float(freq[0]),
        delta_x=step,
        scan_data=0,
        window_applied=1,
        vectors=[Vector(RESPONSE, FORCE, *powers) for _ in range(frfs.n_frf)],
        x=freq.copy(),
        y=np.ascontiguousarray(values)[np.newaxis],
    )


def _spectrum_header(spectra: Spectra, k: int) -> DataHeader:
    """Spectrum ``k`` of the run as a data header of its own (module docstring)."""
    freq = spectra.frequency_hz
    n = freq.size
    step = float(freq[1] - freq[0]) if n > 1 else 0.0
    linear = _same(linear_axis(freq[0], step, n), freq)
    kind = spectra.kinds[k]
    values = spectra.values[k]
    return DataHeader(
        title=spectra.labels[k][:16],
        domain=codes.FREQ_DOMAIN,
        data_type=DATA_TYPES[kind],
        n_points=n,
        last_valid_index=n - 1,
        x_resolution=codes.LINEAR_RES if linear else codes.ARB_PER_DATA_HDR,
        xdata_type=codes.FLOAT64,
        ydata_type=codes.FLOAT64,
        y_is_complex=int(values.dtype.kind == "c"),
        y_is_normalized=int(kind == "coherence"),
        y_is_power=int(kind in ("power", "cross")),
        total_rows=1,
        x_unit=HERTZ,
        y_unit_valid=1,
        y_unit=unit_of(spectra.units[k]),
        first_x=float(freq[0]),
        delta_x=step,
        scan_data=0,
        window_applied=1,
        # No channel: its unit would make the values' unit; the yUnit says it instead.
        vectors=[Vector(-1, -1, 0, 0)],
        x=freq.copy(),
        y=np.ascontiguousarray(values)[np.newaxis, np.newaxis],
    )

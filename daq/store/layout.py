"""Names of everything inside a run file (HDF5), in one place.

The tree is NeXus-flavoured so that generic viewers (h5web, silx, HDFView) show and
plot a run without knowing this program: groups carry ``NX_class``, plottable groups
carry ``signal`` and ``axes``, datasets carry ``units`` and ``long_name``, and the
root's ``default`` leads to the data worth plotting. docs/run-format.md describes
every name below.
"""

from __future__ import annotations

SCHEMA_NAME = "cantilever-daq.run"
# Bumped only for changes an older reader would misread; readers refuse newer versions.
SCHEMA_VERSION = 1
# Version 2 = version 1 plus FRF groups whose `form` is not accelerance. Written only by
# runs that hold such an FRF: a version-1 reader, which knows no `form`, would take a
# receptance for an accelerance, so it must refuse the file instead. Every other run is
# still written as version 1, readable by older software.
SCHEMA_VERSION_FRF_FORMS = 2
READ_SCHEMA_VERSION = SCHEMA_VERSION_FRF_FORMS  # the newest version this code reads

RESULT_SCHEMA_NAME = "cantilever-daq.result"
RESULT_SCHEMA_VERSION = 1
# Version 2 = version 1 plus FRF groups whose `form` is not accelerance. Written only by
# runs that hold such an FRF: a version-1 reader, which knows no `form`, would take a
# receptance for an accelerance, so it must refuse the file instead. Every other run is
# still written as version 1, readable by older software.
SCHEMA_VERSION_FRF_FORMS = 2
READ_SCHEMA_VERSION = SCHEMA_VERSION_FRF_FORMS  # the newest version this code reads

# HDF5 file-format features: exactly those of HDF5 1.10. They checksum every piece
# of metadata (superblock v3, object headers v2, attribute and link heaps, and the
# v4 chunk indexes; the 1.8 format still used unchecksummed v1 B-trees for chunks),
# which is what lets a flipped byte anywhere in the metadata be detected. Capping at
# 1.10 keeps the files readable by every HDF5 library from 1.10 on (HDFView, h5web's
# h5wasm, silx).
LIBVER = ("v110", "v110")

# Filters on every dataset: gzip level 4 (good ratio, fast), shuffle (groups the
# bytes of float64 values so gzip finds the repeats) and fletcher32 (per-chunk
# checksum, verified by HDF5 on every read).
GZIP_LEVEL = 4

# --- root attributes -------------------------------------------------------
ATTR_SCHEMA = "schema"
ATTR_SCHEMA_VERSION = "schema_version"
ATTR_CREATOR = "creator"
ATTR_DEFAULT = "default"
# The listing line of the run as one JSON object (daq/store/summary.py), written at
# seal so that a listing reads one attribute instead of the tree; absent from runs
# sealed before it existed, which are listed from their data as before.
ATTR_SUMMARY = "summary_json"
ATTR_NX_CLASS = "NX_class"
ATTR_SIGNAL = "signal"
ATTR_AXES = "axes"
ATTR_AUX_SIGNALS = "auxiliary_signals"
ATTR_UNITS = "units"
ATTR_LONG_NAME = "long_name"

# --- groups ---------------------------------------------------------------
ENTRY = "entry"
INSTRUMENT = "entry/instrument"
SAMPLE = "entry/sample"
HITS = "entry/hits"
ANALYZER = "entry/analyzer"
MEASURED_FRF = "entry/measured_frf"
SPECTRA = "entry/spectra"

# --- /entry attributes ------------------------------------------------------
ENTRY_ATTRS = ("run_id", "kind", "complete", "start_time", "end_time", "operator", "note")
ATTR_SOFTWARE = "software"
ATTR_PROVENANCE = "provenance_json"
# Where the run was measured (model.RunPoints), optional: absent from runs written before
# points existed, which read as model.default_points of their sample (the seed's beam,
# hammer and sensor at the tip). The last three come together or not at all.
ATTR_TEST = "test"  # text: the modal test the run was measured for, "" when none
ATTR_ARTICLE = "article_json"  # JSON object: the test article (model.check_article)
ATTR_FORCE_POINT = "force_point_json"  # JSON object: {name, position_m | node, direction}
ATTR_RESPONSE_POINTS = "response_points_json"  # JSON list of such objects, one per response
POINTS_ATTRS = (ATTR_ARTICLE, ATTR_FORCE_POINT, ATTR_RESPONSE_POINTS)

# --- /entry/instrument attributes -------------------------------------------
INSTRUMENT_ATTRS = ("model", "identification", "resource", "transport", "dialect")
ATTR_SETTINGS = "settings_json"

# --- /entry/sample attributes (SI units are in the names) ---------------------
SAMPLE_ATTRS = (
    "density_kg_m3",
    "youngs_modulus_pa",
    "width_m",
    "height_m",
    "length_m",
    "area_m2",
    "second_moment_m4",
)
SAMPLE_OPTIONAL_ATTRS = ("force_position_m", "sensor_position_m")

# --- /entry/hits ----------------------------------------------------------------
HITS_ATTRS = ("sample_rate_hz", "start_s", "center_hz")
D_FORCE = "force"  # (n_hits, n_samples) N, float64 or complex128
D_RESPONSE = "response"  # (n_hits, n_samples) m/s^2
D_TIME = "time"  # (n_samples,) s relative to the trigger
D_HIT = "hit"  # (n_hits,) hit index 0..n-1, the first axis for viewers
D_ACCEPTED = "accepted"  # (n_hits,) bool
D_REJECT_REASON = "reject_reason"  # (n_hits,) UTF-8 text, "" when accepted
D_OVERLOAD = "overload"  # (n_hits, 2) bool: [force channel, response channel]
D_PEAK_FORCE = "peak_force"  # (n_hits,) N
D_TIMESTAMP = "timestamp"  # (n_hits,) ISO 8601 UTC text
D_CHECKS = "checks_json"  # (n_hits,) one JSON object per hit

# --- FRF groups (/entry/analyzer and /entry/measured_frf) ------------------------
D_FREQUENCY = "frequency"  # (n_lines,) Hz
D_FRF = "frf"  # (n_frf, n_lines) complex128, (m/s^2)/N
D_COHERENCE = "coherence"  # (n_frf, n_lines) dimensionless
D_LABEL = "label"  # (n_frf,) UTF-8 text
D_FRF_INDEX = "frf_index"  # (n_frf,) 0..n-1, the first axis for viewers
# Group attribute: "receptance", "mobility" or "accelerance"; absent (runs written before
# it existed) means accelerance.
ATTR_FRF_FORM = "form"

# --- /entry/spectra (optional; spectra that are not FRFs) --------------------------
# D_FREQUENCY and D_LABEL as in the FRF groups, and:
D_SPECTRUM = "spectrum"  # (n_traces, n_lines) float64 or complex128, in each trace's unit
D_SPECTRUM_INDEX = "spectrum_index"  # (n_traces,) 0..n-1, the first axis for viewers
D_KIND = "kind"  # (n_traces,) UTF-8 text: power, linear, cross, coherence, other
D_UNIT = "unit"  # (n_traces,) UTF-8 text: each trace's unit ("" for coherence)

# --- result files ---------------------------------------------------------------
RESULT_GROUP = "result"
D_RESULT_JSON = "values_json"  # the non-array part of a result payload, one JSON text

# --- file names in a store folder ------------------------------------------------
RUN_SUFFIX = ".h5"
TMP_PREFIX = "."  # temporaries are hidden files: ".<run_id>.h5.tmp-<pid>-<hex>"
TMP_MARKER = ".tmp-"
INDEX_FILE = ".index.sqlite"

"""Reading user-supplied input files: damping matrices and beam properties."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path
from typing import TYPE_CHECKING

from daq.workflows.errors import WorkflowError

if TYPE_CHECKING:
    import numpy as np

    from analysis.beam import BeamProperties

#: Largest damping matrix / Ritz model accepted: beyond ~60 functions M is too
#: ill-conditioned (cond > 1e13) for the eigenvalues to mean much.
MAX_FUNCTIONS = 60


#: Input files are small tables; anything larger is a wrong file, not a beam.
MAX_INPUT_BYTES = 1_000_000


def _check_file(path: Path) -> None:
    try:
        info = path.stat()
    except FileNotFoundError:
        raise WorkflowError(f"{path}: no such file") from None
    except OSError as exc:
        raise WorkflowError(f"{path}: cannot read ({exc.strerror})") from None
    if path.is_dir():
        raise WorkflowError(f"{path}: is a directory, expected a file")
    if not path.is_file():
        raise WorkflowError(f"{path}: not a regular file")
    if info.st_size > MAX_INPUT_BYTES:
        raise WorkflowError(
            f"{path}: {info.st_size} bytes is too large for this input (limit {MAX_INPUT_BYTES})"
        )


def _read_text(path: Path) -> str:
    _check_file(path)
    try:
        # utf-8-sig: a spreadsheet's CSV export often starts with a byte-order mark.
        return path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise WorkflowError(f"{path}: not a UTF-8 text file") from None
    except OSError as exc:
        raise WorkflowError(f"{path}: cannot read ({exc.strerror})") from None


def read_damping_matrix(path: Path) -> np.ndarray:
    """An N x N damping matrix (N s/m) from .npy, .json or a text table.

    JSON: a list of rows, or an object with a ``damping_matrix`` list of rows.
    Text: one row per line, numbers separated by spaces or commas, ``#`` comments.
    """
    # numpy loads here, not with `daq --help` (daq/cli/commands/model.py imports MAX_FUNCTIONS).
    import numpy as np

    if path.suffix.lower() == ".npy":
        _check_file(path)
        try:
            values = np.load(path, allow_pickle=False)
        except (OSError, ValueError, EOFError) as exc:
            raise WorkflowError(f"{path}: not a readable .npy array ({exc or 'empty file'})") from None
        if not isinstance(values, np.ndarray) or values.dtype.kind not in "iuf":
            raise WorkflowError(f"{path}: the damping matrix must hold real numbers")
    elif path.suffix.lower() == ".json":
        try:
            data = json.loads(_read_text(path))
        except json.JSONDecodeError as exc:
            raise WorkflowError(f"{path}: invalid JSON at line {exc.lineno}: {exc.msg}") from None
        if isinstance(data, dict):
            if "damping_matrix" not in data:
                raise WorkflowError(f"{path}: a JSON object must hold a 'damping_matrix' list of rows")
            data = data["damping_matrix"]
        values = _rows_to_array(data, path)
    else:
        rows = []
        for lineno, line in enumerate(_read_text(path).splitlines(), start=1):
            line = line.split("#", 1)[0].replace(",", " ").strip()
            if not line:
                continue
            try:
                rows.append([float(tok) for tok in line.split()])
            except ValueError:
                raise WorkflowError(f"{path}:{lineno}: not a row of numbers: {line!r}") from None
        values = _rows_to_array(rows, path)
    return _check_matrix(np.asarray(values), path)


def _rows_to_array(rows: object, path: Path) -> np.ndarray:
    import numpy as np

    if not isinstance(rows, list) or not rows or not all(isinstance(r, list) for r in rows):
        raise WorkflowError(f"{path}: expected a non-empty list of rows")
    lengths = {len(r) for r in rows}
    if len(lengths) != 1:
        raise WorkflowError(f"{path}: rows have different lengths {sorted(lengths)}")
    # JSON true/false and "1.5" would pass np.array(..., float): refuse them.
    if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for r in rows for v in r):
        raise WorkflowError(f"{path}: every entry must be a number")
    try:
        return np.array(rows, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise WorkflowError(f"{path}: every entry must be a finite number") from None


def _check_matrix(values: np.ndarray, path: Path) -> np.ndarray:
    import numpy as np

    if values.ndim != 2 or values.shape[0] != values.shape[1]:
        shape = "x".join(str(s) for s in values.shape) or "a scalar"
        raise WorkflowError(f"{path}: the damping matrix must be square, got {shape}")
    values = values.astype(float)
    if not np.all(np.isfinite(values)):
        raise WorkflowError(f"{path}: the damping matrix holds non-finite values")
    if not 1 <= values.shape[0] <= MAX_FUNCTIONS:
        raise WorkflowError(f"{path}: the damping matrix must be 1x1 to {MAX_FUNCTIONS}x{MAX_FUNCTIONS}")
    return values


def read_beam(path: Path) -> BeamProperties:
    """Beam properties from a TOML or JSON table of field names (SI units); missing
    fields keep the seed's Table 1 values."""
    from analysis.beam import BeamProperties

    text = _read_text(path)
    try:
        data = json.loads(text) if path.suffix.lower() == ".json" else tomllib.loads(text)
    except json.JSONDecodeError as exc:
        raise WorkflowError(f"{path}: invalid JSON at line {exc.lineno}: {exc.msg}") from None
    except tomllib.TOMLDecodeError as exc:
        raise WorkflowError(f"{path}: invalid TOML: {exc}") from None
    if isinstance(data, dict) and isinstance(data.get("beam"), dict):
        outside = sorted(set(data) - {"beam"})
        if outside:
            raise WorkflowError(f"{path}: keys outside the [beam] table: {', '.join(outside)}")
        data = data["beam"]
    if not isinstance(data, dict):
        raise WorkflowError(f"{path}: expected a table of beam properties")
    try:
        return BeamProperties.from_dict(data)
    except (TypeError, ValueError, OverflowError) as exc:
        raise WorkflowError(f"{path}: {exc}") from None

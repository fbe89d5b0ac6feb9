"""Small helpers shared by the gagekit modules (array checks, JSON, TOML files)."""

from __future__ import annotations

import json
import math
from dataclasses import asdict, is_dataclass
import sys
from pathlib import Path
from typing import Any, Iterator, Mapping, Optional, Sequence, Union

import numpy as np

from .errors import ConfigError, ConfigFileError, InvalidInputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


LENGTH_RESOLUTION_MM = 1e-9
"""Resolution of computed lengths (mm): a result within it of a limit is on the limit (an LP
that places a face on its gage returns +-1e-14 mm, not 0); 1 pm, far below any scanner's
noise and far above the rounding of double-precision coordinates of parts up to 10 m."""


def as_points(points: Any, dim: int = 3, what: str = "points") -> np.ndarray:
    """Return ``points`` as a C-contiguous float64 array of shape (n, dim).

    Raises :class:`InvalidInputError` for a wrong shape or a non-numeric dtype.
    Finiteness is checked by the Rust kernels (they name the offending row).
    """
    try:
        arr = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"{what}: cannot be read as numbers ({exc})") from None
    if arr.ndim != 2 or arr.shape[1] != dim:
        raise InvalidInputError(f"{what}: expected an (n, {dim}) array, got shape {arr.shape}")
    return np.ascontiguousarray(arr)


def check_finite(arr: np.ndarray, what: str = "points") -> None:
    """Raise :class:`InvalidInputError` naming the first row with NaN or inf, and its values
    (the one finite check of the Python package for input arrays; the kernels have
    ``gagekit_core::check_finite`` for theirs)."""
    if np.isfinite(arr).all():  # flat: several times faster than a per-row reduction
        return
    bad = ~np.isfinite(arr)
    row = int(np.argmax(bad.any(axis=1))) if arr.ndim == 2 else int(np.argmax(bad))
    values = arr[row].tolist() if arr.ndim == 2 else arr[row].item()
    raise InvalidInputError(f"{what}: point {row} has a non-finite coordinate {values} (NaN or inf)")


def to_jsonable(obj: Any) -> Any:
    """Convert results (dataclasses, numpy scalars and arrays) to JSON-ready values."""
    if hasattr(obj, "to_dict") and callable(obj.to_dict):
        return to_jsonable(obj.to_dict())
    if is_dataclass(obj) and not isinstance(obj, type):
        return to_jsonable(asdict(obj))
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        return to_jsonable(obj.item())
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def find_nonfinite(obj: Any, path: str = "") -> Optional[str]:
    """The path (``a.b[3]``) of the first NaN or infinity in a result (dataclasses,
    ``to_dict()`` objects, dicts, lists, numpy arrays and scalars), or None."""
    if hasattr(obj, "to_dict") and callable(obj.to_dict):
        return find_nonfinite(obj.to_dict(), path)
    if is_dataclass(obj) and not isinstance(obj, type):
        return find_nonfinite(asdict(obj), path)
    if isinstance(obj, dict):
        for k, v in obj.items():
            hit = find_nonfinite(v, f"{path}.{k}" if path else str(k))
            if hit is not None:
                return hit
        return None
    if isinstance(obj, (list, tuple)):
        for i, v in enumerate(obj):
            hit = find_nonfinite(v, f"{path}[{i}]")
            if hit is not None:
                return hit
        return None
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind in "fc":
            bad = ~np.isfinite(obj)
            if bad.any():
                idx = np.unravel_index(int(np.argmax(bad)), obj.shape)
                return f"{path}[{', '.join(map(str, idx))}]"
            return None
        if obj.dtype.kind == "O":
            return find_nonfinite(obj.tolist(), path)
        return None
    if isinstance(obj, (float, np.floating)) and not math.isfinite(float(obj)):
        return path or "value"
    return None


def check_finite_result(obj: Any, what: str = "result") -> Any:
    """Return ``obj`` if every number in it is finite; :class:`NumericalError` naming the
    first NaN or infinity otherwise (a result is checked before it is returned or printed)."""
    from .errors import NumericalError

    hit = find_nonfinite(obj)
    if hit is not None:
        raise NumericalError(f"{what}: the computation produced a non-finite value at {hit} "
                             "(NaN or infinity): the input is out of the range this method handles")
    return obj


def dumps(obj: Any) -> str:
    """JSON text of a result, strict (no NaN), stable key order as produced."""
    return json.dumps(to_jsonable(obj), indent=2, allow_nan=False)


def load_toml(path: Union[str, Path], what: str = "TOML") -> dict:
    """Parse the TOML file ``path`` (a ``what`` file: machine, gage, zones, ...): the one TOML
    reader of the package. A file that cannot be read raises
    :class:`~gagekit.errors.FileAccessError` (or FileFormatError for non-UTF-8 bytes), invalid
    TOML :class:`~gagekit.errors.ConfigFileError`, each naming the file and the problem."""
    return parse_toml(read_text(path, what), str(path))


def read_text(path: Union[str, Path], what: str) -> str:
    """The UTF-8 text of a ``what`` file, through the one file boundary
    (:func:`gagekit._files.read_text`): typed errors for a missing file, a folder, a FIFO
    (never opened, so never a hang), permissions and non-UTF-8 bytes."""
    from ._files import read_text as _read_text

    return _read_text(path, f"{what} file")


def parse_toml(text: str, source: str) -> dict:
    """Parse TOML text; ConfigFileError naming ``source`` if it is not valid TOML."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigFileError(f"{source}: not valid TOML ({exc})") from None


def named_tables(tables: Sequence[Any], kind: str, source: str) -> Iterator[tuple[str, Mapping]]:
    """The ``[[kind]]`` tables of a TOML file as (name, table): each must be a table with a
    non-empty ``name`` not used before; otherwise a ConfigError naming the file and the table."""
    if not isinstance(tables, (list, tuple)):
        raise ConfigError(f"{source}: {kind} must be given as [[{kind}]] tables, got {tables!r}")
    seen: set[str] = set()
    for k, t in enumerate(tables):
        if not isinstance(t, Mapping):
            raise ConfigError(f"{source}: {kind} #{k + 1} must be a table")
        name = t.get("name")
        if not isinstance(name, str) or not name:
            raise ConfigError(f"{source}: {kind} #{k + 1} needs a name")
        if name in seen:
            raise ConfigError(f"{source}: {kind} '{name}' is defined twice")
        seen.add(name)
        yield name, t

"""A data set's ``meta.yaml`` (and any YAML side file): read safely, its keys checked.

Every problem is a :class:`benchmark.core.errors.DataError` naming the file and the key; the
file is read with the size limit and the encodings of :mod:`benchmark.core.tables`.
"""

from __future__ import annotations

import math
from pathlib import Path

import yaml

from benchmark.core.errors import DataError
from benchmark.core.spelling import found_instead
from benchmark.core.tables import MAX_YAML_BYTES, _one_line, _short_repr, read_text


def read_yaml(path: Path, max_bytes: int = MAX_YAML_BYTES):
    """Parse a YAML file (safe loader). Whatever it holds, the result is the document or a
    DataError: also for YAML that parses but cannot be built (an impossible date, deep
    nesting)."""
    text = read_text(path, max_bytes=max_bytes, what="YAML file")
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise DataError(path, f"not valid YAML: {_one_line(exc)}") from None
    except (ValueError, TypeError, OverflowError, RecursionError) as exc:
        # e.g. 'date: 2001-02-30' (the safe loader builds dates), or thousands of nested '['
        raise DataError(path, f"not valid YAML: {type(exc).__name__}: {_one_line(exc)}") from None


def read_meta(folder: Path, required: dict[str, type | tuple[type, ...]]) -> dict:
    """Read ``folder/meta.yaml`` and check that each required key is present with a usable type."""
    folder = Path(folder)
    path = folder / "meta.yaml"
    if not folder.is_dir():
        where = "" if folder.is_absolute() else f" (a relative path, read from {Path.cwd()}: {folder.absolute()})"
        raise DataError(folder, f"data set folder does not exist{where}" if not folder.exists()
                        else "is not a folder: data.path names a data set folder (meta.yaml + CSV tables)")
    if not path.exists():
        raise DataError(path, "missing: every data set folder needs a meta.yaml (docs/data_format.md)")
    meta = read_yaml(path)
    if not isinstance(meta, dict):
        raise DataError(path, f"must be a mapping of keys to values, got {type(meta).__name__}")
    for key, kind in required.items():
        if key not in meta:
            raise DataError(path, f"missing key '{key}'" + found_instead(key, [str(k) for k in meta]))
        meta[key] = check_meta_type(path, key, meta[key], kind)
    return meta


def check_meta_type(path: Path, key: str, value, kind):
    """Check a meta.yaml value's type and return it (a float written as ``1e-3``, which YAML
    reads as a string, is accepted as the number). Numbers must be finite; a float key gets
    a Python float (an integer too large for a float is refused)."""
    kinds = kind if isinstance(kind, tuple) else (kind,)
    if float in kinds and isinstance(value, str):
        try:
            value = float(value.strip())
        except ValueError:
            pass
    ok = any(
        isinstance(value, k) and not (k in (int, float) and isinstance(value, bool)) for k in kinds
    )
    if float in kinds and isinstance(value, int) and not isinstance(value, bool):
        ok = True
    if not ok:
        names = " or ".join(k.__name__ for k in kinds)
        raise DataError(path, f"key '{key}' must be {names}, got {_short_repr(value)}")
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        try:
            finite = math.isfinite(value)
        except OverflowError:
            finite = False
        if not finite or abs(value) > 1e300:
            raise DataError(path, f"key '{key}' must be a finite number of sensible size, "
                                  f"got {_short_repr(value)}")
        if float in kinds and int not in kinds:
            value = float(value)
    return value


#: Keys of ``nameplate`` in meta.yaml: rated power (W), voltage (V line-line rms), current (A rms),
#: speed (rpm), frequency (Hz).
NAMEPLATE_KEYS = ("rated_power", "voltage", "current", "speed", "frequency")


def parse_nameplate(meta_path: Path, value) -> dict:
    """``nameplate`` of meta.yaml: a mapping of positive numbers with known keys."""
    if not isinstance(value, dict):
        raise DataError(meta_path, f"key 'nameplate' must be a mapping of {list(NAMEPLATE_KEYS)}, got "
                                   f"{_short_repr(value)}")
    out = {}
    for k, v in value.items():
        if k not in NAMEPLATE_KEYS:
            raise DataError(meta_path, f"key 'nameplate.{k}' unknown{found_instead(str(k), NAMEPLATE_KEYS)}; "
                                       f"known: {list(NAMEPLATE_KEYS)}")
        x = check_meta_type(meta_path, f"nameplate.{k}", v, float)
        if not x > 0:
            raise DataError(meta_path, f"key 'nameplate.{k}' must be > 0, got {x}")
        out[k] = float(x)
    return out

"""A synthetic data set's ``truth.yaml``, read only to score an identification's errors (the
problem's ``truth`` hook, ``conf/problem/timedomain.yaml``); the diagnosis never opens it."""

from __future__ import annotations

import math
from pathlib import Path

import yaml

from benchmark.core.errors import DataError
from benchmark.problems.timedomain.motor import PARAMETER_NAMES


def read_truth_for_scoring(folder) -> dict | None:
    """The true parameters of a synthetic data set, read only to score errors.

    A malformed truth.yaml only costs the scoring: it raises DataError naming the file, since
    a user who put it there expects errors to be scored."""
    path = Path(folder) / "truth.yaml"
    if not path.is_file():
        return None
    try:
        doc = yaml.safe_load(path.read_text(encoding="utf-8-sig"))
    except (yaml.YAMLError, UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise DataError(path, f"not valid YAML: {str(exc).splitlines()[0]}") from None
    params = doc.get("parameters") if isinstance(doc, dict) else None
    if not isinstance(params, dict):
        raise DataError(path, "needs a mapping 'parameters' of true values (or remove the file)")
    out = {}
    for k, v in params.items():
        if k not in PARAMETER_NAMES:
            continue
        try:
            value = float(v)
        except (TypeError, ValueError):
            raise DataError(path, f"parameters.{k} must be a number, got {v!r}") from None
        if math.isfinite(value):
            out[k] = value
    return out


def read_truth_document(folder) -> dict | None:
    """``{"parameters": ...}`` of a synthetic data set's truth.yaml, or None (scoring only)."""
    params = read_truth_for_scoring(folder)
    return None if params is None else {"parameters": params}

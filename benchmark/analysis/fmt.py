"""Number formatting shared by the summary's tables and rankings."""

from __future__ import annotations

import math
import re


def _g(x, digits=4) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    if isinstance(x, float) and math.isinf(x):
        return "inf"
    return f"{x:.{digits}g}"


def _pct(x) -> str:
    return "–" if x is None or math.isnan(x) else f"{100 * x:.3g} %"


def _signed_pct(x) -> str:
    return "–" if x is None or math.isnan(x) else f"{100 * x:+.3g} %"


def _slug(s: str) -> str:
    return re.sub(r"[^A-Za-z0-9]+", "_", s).strip("_") or "problem"

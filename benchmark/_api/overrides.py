"""Keyword arguments of the API as Hydra overrides: ``budget=2000`` -> ``"budget=2000"``,
``problem__stator_resistance="prior"`` -> ``"problem.stator_resistance=prior"`` (a double
underscore stands for the dot of a nested key), ``optimizer="scipy_de"`` -> a group choice.
The values are written in Hydra's override grammar, so that the configuration composed from
them is the one the same keys give on the command line."""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from pathlib import Path

from benchmark.core.errors import ConfigError

_PLAIN = re.compile(r"[A-Za-z_/][\w./\-]*")
_RESERVED = ("true", "false", "null", "inf", "nan")


def override_value(value) -> str:
    """``value`` in Hydra's override grammar (quoted strings, ``[...]`` lists, ``{k: v}`` maps)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(float(value))
    if isinstance(value, Path):
        value = str(value)
    if isinstance(value, str):
        if _PLAIN.fullmatch(value) and value.lower() not in _RESERVED:
            return value
        return "'" + value.replace("\\", "\\\\").replace("'", "\\'") + "'"
    if isinstance(value, Mapping):
        return "{" + ",".join(f"{_key(k)}:{override_value(v)}" for k, v in value.items()) + "}"
    if isinstance(value, list | tuple):
        return "[" + ",".join(override_value(v) for v in value) + "]"
    if hasattr(value, "item"):  # a numpy scalar
        return override_value(value.item())
    raise ConfigError(f"cannot pass a {type(value).__name__} as a configuration value: {value!r}")


def _key(k) -> str:
    k = str(k)
    if not re.fullmatch(r"\w+", k):
        raise ConfigError(f"{k!r}: a mapping key in a configuration value must be a plain name")
    return k


def to_overrides(kwargs: Mapping, added_groups=()) -> list[str]:
    """``["key=value", ...]`` for keyword arguments (``a__b=1`` sets the nested key ``a.b``); a
    group of ``added_groups`` (one the configuration does not select by default, such as
    ``experiment``) is added with ``+``, as on the command line."""
    out = []
    for name, value in kwargs.items():
        prefix = "+" if name in added_groups else ""
        if not re.fullmatch(r"[A-Za-z_]\w*", name) or name.startswith("_") or "___" in name:
            raise ConfigError(f"{name}: not a configuration key (nested keys are joined by a double underscore, "
                              "e.g. problem__stator_resistance='prior')")
        out.append(f"{prefix}{name.replace('__', '.')}={override_value(value)}")
    return out

"""When each channel of a record was sampled: the acquisition's documented channel skew.

A card samples its channels at once (no skew), or one after the other (a multiplexed card: each
channel a documented fraction of a sample after the sample instant). ``meta.yaml`` states it as
``channel_skew`` (samples, positive when a channel is sampled late, i.e. its reading is the value
that much earlier):

* a number, or ``[low, high]``: the current channels' skew behind the voltage channels;
* a mapping of phase channels (:data:`SKEWED_CHANNELS`) to their own skews, the card's sequence,
  e.g. ``{i_r: 0.0, v_r: 0.2, i_s: 0.4, v_s: 0.6, v_t: 0.8}`` for five channels converted in
  that order at 0.2 samples apart. Channels not named are sampled at the instant (0).

The voltage channels of a mapping are put back on the sample instants when the record is read
(:func:`realign`: the voltages drive the model, and a known skew is a fact, not a finding); the
current channels' skews stay in the record, and the ``channel_delay`` effect fits them within
the documentation's tolerance where they earn their place
(:class:`benchmark.problems.timedomain.bench_effects.ChannelDelay`).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from benchmark.core.errors import DataError
from benchmark.core.meta_file import check_meta_type
from benchmark.core.spelling import found_instead
from benchmark.core.tables import _short_repr
from benchmark.problems.timedomain.frames import SQRT3

#: Largest channel skew meta.yaml may state, samples (a multiplexed card's whole sequence).
MAX_CHANNEL_SKEW = 8.0
#: Phase channels a ``channel_skew`` mapping may name (a record's phase columns).
SKEWED_CHANNELS = ("i_r", "i_s", "v_r", "v_s", "v_t")
CURRENT_CHANNELS = ("i_r", "i_s")
VOLTAGE_CHANNELS = ("v_r", "v_s", "v_t")


def parse_channel_skew(meta_path: Path, value) -> float | tuple[float, float] | dict[str, float]:
    """``channel_skew`` of meta.yaml: a number, ``[low, high]`` or a mapping of
    :data:`SKEWED_CHANNELS` to samples, each within :data:`MAX_CHANNEL_SKEW`."""
    if isinstance(value, Mapping):
        out = {}
        for k, v in value.items():
            if k not in SKEWED_CHANNELS:
                raise DataError(meta_path, f"key 'channel_skew.{k}' unknown{found_instead(str(k), SKEWED_CHANNELS)}; "
                                           f"a channel_skew mapping names phase channels {list(SKEWED_CHANNELS)}")
            out[str(k)] = check_meta_type(meta_path, f"channel_skew.{k}", v, float)
        values = tuple(out.values())
    elif isinstance(value, (list, tuple)):
        if len(value) != 2:
            raise DataError(meta_path, f"key 'channel_skew' must be a number, [low, high] or a mapping of channels "
                                       f"to samples, got {_short_repr(value)}")
        values = tuple(check_meta_type(meta_path, "channel_skew", v, float) for v in value)
        out = (min(values), max(values))
    else:
        values = (check_meta_type(meta_path, "channel_skew", value, float),)
        out = values[0]
    if not all(abs(v) <= MAX_CHANNEL_SKEW for v in values):
        raise DataError(meta_path, f"key 'channel_skew' must be within +-{MAX_CHANNEL_SKEW:g} samples, got "
                                   f"{_short_repr(value)}")
    return out


def check_mapping_columns(meta_path: Path, skew, columns: dict) -> None:
    """A mapping's channels must be the record's phase columns (``columns`` of a
    :class:`StartupRecord`): a skew of ``v_r`` says nothing about a recorded ``v_alpha``."""
    if not isinstance(skew, Mapping):
        return
    for group, names, phase_cols in (("voltage", VOLTAGE_CHANNELS, "v_r, v_s, v_t"),
                                     ("current", CURRENT_CHANNELS, "i_r, i_s")):
        named = [k for k in names if skew.get(k, 0.0) != 0.0]
        if named and columns.get(group) != phase_cols:
            raise DataError(meta_path, f"key 'channel_skew' gives {named} a skew, but the records hold "
                                       f"{columns.get(group)}: state per-channel skews for phase columns")


def current_lags(skew) -> tuple[float, float] | None:
    """The current channels' skews ``(i_r, i_s)`` of a mapping, samples, relative to the
    voltages once those are realigned; None for a number, a range or no mapping."""
    if not isinstance(skew, Mapping):
        return None
    return float(skew.get("i_r", 0.0)), float(skew.get("i_s", 0.0))


def realign(v3: np.ndarray, skew) -> np.ndarray:
    """Phase voltages ``v3`` (N, 3: r, s, t) with a mapping's voltage skews undone: each channel
    moved back by its skew (its value at the sample instant), by :func:`fractional_delay`."""
    if not isinstance(skew, Mapping):
        return v3
    lags = np.array([float(skew.get(k, 0.0)) for k in VOLTAGE_CHANNELS])
    if not np.any(lags):
        return v3
    x = np.ascontiguousarray(np.asarray(v3, float).T[:, None, :])  # (3 channels, 1, N)
    return fractional_delay(x, -lags)[:, 0, :].T


def delay_phase_currents(i_ab: np.ndarray, lags: np.ndarray) -> np.ndarray:
    """Alpha-beta currents ``i_ab`` (n, 2, N) whose phase channels ``i_r``, ``i_s`` are each
    delayed by their own skew ``lags`` (n, 2) samples (the third phase from a zero sum, as the
    record's is)."""
    a, b = i_ab[:, 0, :], i_ab[:, 1, :]
    phases = np.stack([a, -0.5 * a + 0.5 * SQRT3 * b], axis=1)  # i_r, i_s
    out = np.empty_like(phases)
    for k in range(2):
        out[:, k:k + 1, :] = fractional_delay(np.ascontiguousarray(phases[:, k:k + 1, :]), lags[:, k])
    res = np.empty_like(i_ab)
    res[:, 0, :] = out[:, 0, :]
    res[:, 1, :] = (out[:, 0, :] + 2.0 * out[:, 1, :]) / SQRT3
    return res


def fractional_delay(x: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``x`` (n, c, N) delayed by ``d`` (n,) samples (may be negative or fractional): 4-point
    Lagrange interpolation, zeros before the record (at rest), the last value after it."""
    n, c, N = x.shape
    pad = int(np.ceil(np.max(np.abs(d)))) + 3 if len(d) else 3
    xp = np.concatenate([np.zeros((n, c, pad)), x, np.repeat(x[:, :, -1:], pad, axis=2)], axis=2)
    out = np.empty_like(x)
    k = np.arange(N)
    for m in range(n):
        dm = float(d[m])
        if not np.isfinite(dm):
            out[m] = np.nan
            continue
        u = k - dm + pad  # position in xp
        b = np.floor(u).astype(int)
        t = u - b
        w_m1 = -t * (t - 1.0) * (t - 2.0) / 6.0
        w_0 = (t + 1.0) * (t - 1.0) * (t - 2.0) / 2.0
        w_1 = -(t + 1.0) * t * (t - 2.0) / 2.0
        w_2 = (t + 1.0) * t * (t - 1.0) / 6.0
        xm = xp[m]
        out[m] = w_m1 * xm[:, b - 1] + w_0 * xm[:, b] + w_1 * xm[:, b + 1] + w_2 * xm[:, b + 2]
    return out

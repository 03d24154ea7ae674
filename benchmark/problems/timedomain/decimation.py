"""Start-up records sampled far faster than the model needs, read at a ``k`` times longer sample
time (``decimate`` in ``meta.yaml``).

The model steps once per sample (RK4, the voltage linear between samples, or held); at the
10-12 kHz of the project's records it is within 0.001 of eight sub-steps
(``docs/diagnosis_engine.md``). A record sampled at 48 kHz costs four times the simulations of
every fit, and the identification and the diagnosis take four to ten times as long, for nothing
the motor's dynamics carry above a few kilohertz. ``decimate: k`` keeps every ``k``-th sample
time (the first one included, so the supply's switch-on stays where it was):

* the voltage, the model's input: a sampled one (``linear``) keeps its own samples, points of
  a continuous voltage whose volt-seconds the conditioning restores as for any sampled voltage
  (``chord_voltage`` is dropped); a held one (``zoh``) becomes its mean over each new interval
  (the interval's volt-seconds exactly, a switching step inside it included);
* the measured outputs (currents, speed, a torque) of a sampled supply are the mean over the
  new sample interval centred on the kept time (``k`` samples; for an even ``k``, ``k + 1``
  with the two ends at half weight; the record's first and last values repeated beyond its
  ends): white noise's variance falls by ``k`` as the samples do, so the information on the
  motor's slow signals stays, and a sine of ``w`` reads ``(w k Ts)^2 / 24`` low (3e-5 at 50 Hz
  and 12 kHz after), the model's point value against a mean; at the switch-on's first sample the
  mean holds an eighth of a new interval's current rise, one sample's misfit. Under a held
  voltage the current bends at every switching step, and a mean about a bend is not the
  model's point value (six-step at 48 kHz read at 12 kHz: 1.27 times the noise): there the
  outputs are the samples themselves, and their standard errors those of a record sampled at
  the new rate;
* a stated ``channel_skew`` (samples) is divided by ``k``; a stated ``speed_filter`` (s) stays
  (the centred mean adds no lag, only a smoothing over one new sample).

Not for an inverter's pulse-width-modulated voltage sampled to show its pulses: held as interval
means, the pulses' current ripple is not in the model. The stop record is read at
:data:`STOP_SAMPLE_TIME` wherever it is sampled faster, ``decimate`` or not (:func:`stop_read`).
:func:`suggested_factor` gives the largest factor that keeps the rate the model is validated at;
the loader suggests it for a sampled (``linear``) supply.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from benchmark.core.errors import DataError, DataWarning

#: The stop record's sample time read (s): a coast's dynamics take seconds (the spec's and the generator's
#: 1 ms); more samples only weigh the stop more in every score pooled over the records' residuals.
STOP_SAMPLE_TIME = 1e-3
#: The sampling rate the model is validated at (Hz): the project's records are 10.8-12 kHz.
VALIDATED_RATE_HZ = 10_000.0
#: ... and at least this many samples per supply period (200 at 50 Hz is 10 kHz).
MIN_SAMPLES_PER_PERIOD = 200


def target_rate(supply_frequency: float | None) -> float:
    """The lowest sampling rate (Hz) the model is validated at for a supply of ``supply_frequency`` Hz."""
    return max(VALIDATED_RATE_HZ, MIN_SAMPLES_PER_PERIOD * float(supply_frequency or 0.0))


def suggested_factor(sample_time: float, supply_frequency: float | None) -> int:
    """The largest ``k`` whose block means still sample at :func:`target_rate` or faster (1: none)."""
    return max(1, int(np.floor((1.0 / sample_time) / target_rate(supply_frequency) * (1 + 1e-9))))


def interval_means(x: np.ndarray | None, k: int) -> np.ndarray | None:
    """Means of ``x`` over ``k`` samples centred on every ``k``-th sample (the first included;
    an even ``k`` takes ``k + 1`` samples, the two ends at half weight; ``x``'s end values
    repeated beyond its ends)."""
    if x is None:
        return None
    w = np.ones(k) / k if k % 2 else np.r_[0.5, np.ones(k - 1), 0.5] / k
    half = (len(w) - 1) // 2
    return np.convolve(np.pad(np.asarray(x, float), half, mode="edge"), w, mode="valid")[::k]


def held_means(x: np.ndarray, k: int) -> np.ndarray:
    """Means of ``x`` over the ``k`` samples from every ``k``-th one on (a held input's volt-seconds
    per new interval; the last interval may be shorter)."""
    x = np.asarray(x, float)
    starts = np.arange(0, len(x), k)
    return np.add.reduceat(x, starts) / np.diff(np.r_[starts, len(x)])


def decimated_record(rec, k: int, held: bool):
    """A :class:`~benchmark.problems.timedomain.data.StartupRecord` at ``k`` times its sample time
    (the module docstring); ``held``: the voltage is held between samples (``zoh``)."""
    def point(x):
        return None if x is None else np.asarray(x, float)[::k]

    volt = (lambda v: held_means(v, k)) if held else point
    out = point if held else (lambda x: interval_means(x, k))
    return dataclasses.replace(
        rec, t=point(rec.t), v_alpha=volt(rec.v_alpha), v_beta=volt(rec.v_beta), i_alpha=out(rec.i_alpha),
        i_beta=out(rec.i_beta), speed=out(rec.speed), torque=out(rec.torque))


def stop_read(stop, step: float):
    """A :class:`~benchmark.problems.timedomain.data.StopRecord` sampled every ``step`` s read at
    :data:`STOP_SAMPLE_TIME` or faster (its speed as means over ``k`` samples centred on every
    ``k``-th one, :func:`interval_means`), and the report's line on it (None: read as recorded).
    A stop sampled at 12 kHz read as recorded outweighs a 1 s start-up twelve times over: the
    diagnosis of a direct start with a double cage and a 10 s stop saw a gap of 2.44 where the same
    stop at 1 kHz gave 4.25, and took 2.3 times the CPU time."""
    k = max(1, min(int(np.floor(STOP_SAMPLE_TIME / step * (1 + 1e-9))), len(stop.t) - 1))  # two samples kept
    if k == 1:
        return stop, None
    read = dataclasses.replace(stop, t=np.asarray(stop.t, float)[::k], speed=interval_means(stop.speed, k))
    return read, (f"{Path(stop.source).name} read at {1e-3 / (k * step):.4g} kHz, its speed as means over {k} "
                  "samples (a coast's dynamics take seconds)")


def startups_read(meta_path: Path, value, startups: list, sample_time: float, hold: str,
                  supply_frequency: float | None) -> tuple[list, int, list[str]]:
    """The start-up records read with ``decimate: value`` of ``meta_path`` (checked,
    :func:`check_factor`): the records, the factor ``k`` and the report's lines. A rate below
    what the model is validated at is a warning too; a sampled (``linear``) record that could be
    read at a longer step gets a warning naming the factor."""
    k = check_factor(meta_path, value, min(len(r.t) for r in startups))
    held = hold == "zoh"
    if k > 1:
        note, below = decimation_note(k, sample_time * k, supply_frequency, held)
        if below:
            warnings.warn(DataWarning.at(meta_path, note), stacklevel=3)
        return [decimated_record(r, k, held) for r in startups], k, [note]
    k_s = suggested_factor(sample_time, supply_frequency)
    if not held and k_s > 1:
        rate = 1e-3 / sample_time
        warnings.warn(DataWarning.at(meta_path, f"the start-up is sampled at {rate:.4g} kHz, where the model needs "
                                                f"{1e-3 * target_rate(supply_frequency):.4g} kHz: decimate: {k_s} "
                                                f"in meta.yaml reads one sample in {k_s} ({rate / k_s:.4g} kHz, the "
                                                f"outputs as means over {k_s}), about {k_s} times faster to fit, "
                                                "with the same information on the motor's dynamics "
                                                "(docs/data_format.md)"), stacklevel=3)
    return startups, 1, []


def skew_decimated(skew, k: int):
    """A ``channel_skew`` (samples: a number, ``(low, high)`` or a mapping) in samples ``k`` times longer."""
    if skew is None:
        return None
    if isinstance(skew, Mapping):
        return {name: float(v) / k for name, v in skew.items()}
    if isinstance(skew, tuple):
        return tuple(float(v) / k for v in skew)
    return float(skew) / k


def check_factor(meta_path: Path, value, n_samples: int) -> int:
    """``decimate`` of meta.yaml: a whole number of samples, 1 (none) or more, leaving at
    least two samples per record (``n_samples``: the shortest start-up record's)."""
    if isinstance(value, float) and value.is_integer():
        value = int(value)  # 4.0
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise DataError(meta_path, f"key 'decimate' must be a whole number of samples (1: none), "
                                   f"got {value!r}")
    k = int(value)
    if k < 1:
        raise DataError(meta_path, f"key 'decimate' must be 1 (none) or more samples, got {k}")
    if n_samples <= k:
        raise DataError(meta_path, f"key 'decimate' {k} leaves one sample of a {n_samples}-sample start-up record")
    return k


def decimation_note(k: int, sample_time: float, supply_frequency: float | None, held: bool) -> tuple[str, bool]:
    """The plain-English line the report gives for a data set read one sample in ``k`` (``sample_time``
    after it, s; ``held``: a held voltage), and whether that is below the rate the model is validated at."""
    rate = 1.0 / sample_time
    note = (f"start-up records read one sample in {k} ({rate * k / 1e3:.4g} kHz -> {rate / 1e3:.4g} kHz, "
            f"meta.yaml decimate), " + ("the held voltage as its mean over each interval" if held else
                                        f"the measured outputs as means over {k} samples"))
    below = rate < target_rate(supply_frequency) * (1 - 1e-9)
    if below:
        note += (f"; below the {target_rate(supply_frequency) / 1e3:.4g} kHz the model is validated at for this "
                 "supply: its own stepping error may show in the fit")
    return note, below

"""From the internal trajectory to the recorded channels: sampling, sensor errors, noise.

Sampling picks internal steps (sample ``k`` is step ``k M``); a channel that lags by ``d``
internal steps reads step ``k M - d`` (before ``t = 0`` the plant is at rest and unsupplied).
That is a fractional-sample skew of ``d/M`` samples done on the oversampled signal, not an
interpolation of the output. Inverter voltages are the switch-state voltages averaged over
the sample (zero-order hold); grid voltages are the terminal voltages at the sample instant.
An optional first-order anti-aliasing filter (``anti_alias`` Hz) runs at the internal rate on
the current, voltage (grid) and speed channels before sampling.

Sensor errors (the effects that live here):

* current probes (``compress``): ``tanh`` ``L tanh(i/L)``; ``knee`` linear to ``L`` then
  ``L + w tanh((|i| - L)/w)``, ``w = L/2``; ``clip`` hard clipping at the acquisition range
  ``L`` (applied after the noise, as the ADC does); held out: ``hall_core`` and
  ``current_transformer`` (:mod:`~synthetic.independent.probes`);
* DC offsets on the current and voltage channels; held out: current offsets that drift as
  each probe warms with its own current, ``o_0 + o_d h(t)/h(T)`` with
  ``h(t) = int_0^t i^2 exp(-(t - s)/tau) ds`` (the probe's offset temperature coefficient
  times the rise of a first-order thermal body heated by ``i^2``);
* tachometer ``g w + offset + a w sin(theta + phi)`` (gain, offset, ripple at the rotation
  frequency of the sensed shaft); held out: ``g F(w) + offset`` with ``F`` the first-order
  RC filter of time constant ``speed_lag`` that smooths a DC tachogenerator's commutator
  ripple (developed on since), and ``g W(w) + offset`` with ``W`` an incremental encoder's
  speed: the angle it turned in the last ``speed_window`` s over that gate time;
* channel timing: besides the lags above, held out: a second-order Bessel anti-aliasing
  filter on the current channels (``current_filter_delay``: its group delay at DC, s), and a
  multiplexed acquisition card whose channels are sampled one after the other
  (``current_delays``, ``voltage_delays``: per phase, internal steps).

Noise (``Noise``): white plus AR(1)-coloured current noise, ADC quantisation of currents and of
measured (grid) voltages, white noise and quantisation of speed, tachometer commutator ripple
``r sin(q theta)``, torque-sensor noise. All drawn from one ``numpy.random.Generator`` in a
fixed order.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np
from scipy.signal import lfilter

from synthetic.independent.probes import current_transformer, hall_core

COMPRESS_FORMS = ("none", "tanh", "knee", "clip", "hall_core", "current_transformer")


@dataclass(frozen=True)
class Noise:
    """Measurement noise (all standard deviations of the recorded samples).

    Parameters
    ----------
    current_white : white current noise, A.
    current_colored : stationary std of the AR(1) current noise, A.
    current_pole : AR(1) coefficient per sample (0..1; larger = lower-frequency noise).
    current_quantum : current ADC step, A (0 = none).
    voltage_white : voltage noise, V (measured grid voltages only).
    voltage_quantum : voltage ADC step, V (measured grid voltages only).
    speed_white : speed noise, rad/s.
    speed_quantum : speed quantisation step, rad/s.
    speed_ripple : tachometer commutator ripple amplitude, rad/s.
    ripple_order : ripple periods per revolution.
    torque_white : torque-sensor noise, N m.
    """

    current_white: float = 0.0
    current_colored: float = 0.0
    current_pole: float = 0.95
    current_quantum: float = 0.0
    voltage_white: float = 0.0
    voltage_quantum: float = 0.0
    speed_white: float = 0.0
    speed_quantum: float = 0.0
    speed_ripple: float = 0.0
    ripple_order: int = 12
    torque_white: float = 0.0

    def describe(self) -> dict:
        return {k: (float(v) if k != "ripple_order" else int(v)) for k, v in asdict(self).items()}


@dataclass(frozen=True)
class Sensors:
    """Sensor chain settings (defaults: ideal sensors, speed recorded, no torque sensor).

    Parameters
    ----------
    compress : one of :data:`COMPRESS_FORMS`.   compress_level : ``L``, A peak.
    current_offset : DC offsets of ``i_r, i_s``, A.   voltage_offset : of ``v_r, v_s, v_t``, V.
    current_delay, voltage_delay : channel lag, internal steps.
    speed_gain, speed_offset (rad/s), speed_ripple_rel, speed_ripple_phase (rad): tachometer.
    has_speed, has_torque : which channels exist.   anti_alias : filter cut-off, Hz (0 = none).
    probe : parameters of a ``hall_core`` (``exponent``, ``coercive`` A) or
        ``current_transformer`` probe (``exponent``, ``secondary_time_constant`` s,
        ``remanence`` per channel, ``w_rated`` rad/s).
    offset_drift : drift of the current offsets over the record, A.   offset_drift_tau : s.
    speed_lag : tachometer filter time constant, s (0 = none).
    speed_window : an encoder's gate time, s (0 = none): the speed read is the mean over it.
    current_filter_delay : anti-aliasing Bessel filter's group delay at DC, s (0 = none).
    current_delays, voltage_delays : per-phase lags of a multiplexed card, internal steps
        (empty = the common lags ``current_delay``, ``voltage_delay``).
    """

    compress: str = "none"
    compress_level: float = math.inf
    current_offset: tuple = (0.0, 0.0)
    voltage_offset: tuple = (0.0, 0.0, 0.0)
    current_delay: int = 0
    voltage_delay: int = 0
    speed_gain: float = 1.0
    speed_offset: float = 0.0
    speed_ripple_rel: float = 0.0
    speed_ripple_phase: float = 0.0
    has_speed: bool = True
    has_torque: bool = False
    anti_alias: float = 0.0
    probe: dict = field(default_factory=dict)
    offset_drift: tuple = (0.0, 0.0)
    offset_drift_tau: float = 1.0
    speed_lag: float = 0.0
    speed_window: float = 0.0
    current_filter_delay: float = 0.0
    current_delays: tuple = ()
    voltage_delays: tuple = ()

    def __post_init__(self):
        if self.compress not in COMPRESS_FORMS:
            raise ValueError(f"compress must be one of {COMPRESS_FORMS}, got {self.compress!r}")


def inverse_clarke(a, b) -> np.ndarray:
    """Phase values R, S, T (columns) of zero-sequence-free alpha-beta values."""
    s3 = math.sqrt(3) / 2
    return np.column_stack([a, -0.5 * a + s3 * b, -0.5 * a - s3 * b])


def compress(i: np.ndarray, form: str, level: float) -> np.ndarray:
    """Probe compression before the noise (``tanh``, ``knee``); ``clip`` is done later."""
    if form == "tanh":
        return level * np.tanh(i / level)
    if form == "knee":
        w = 0.5 * level
        a = np.abs(i)
        return np.where(a <= level, i, np.sign(i) * (level + w * np.tanh((a - level) / w)))
    return i


def probe_reading(i: np.ndarray, sensors: Sensors, dt: float) -> np.ndarray:
    """Readings of the held-out probes (``hall_core``, ``current_transformer``) of the phase
    currents ``i`` (K, 2) sampled every ``dt`` s; other probes: :func:`compress`."""
    pr = sensors.probe
    if sensors.compress == "hall_core":
        return hall_core(i, sensors.compress_level, pr["exponent"], pr["coercive"])
    if sensors.compress == "current_transformer":
        return current_transformer(i, dt, sensors.compress_level, pr["w_rated"], pr["exponent"],
                                   pr["secondary_time_constant"], pr["remanence"])
    return compress(i, sensors.compress, sensors.compress_level)


def bessel_delay(x: np.ndarray, delay: float, h: float) -> np.ndarray:
    """``x`` (rows every ``h`` s, from rest) through a second-order Bessel low-pass whose group
    delay at DC is ``delay`` s (``scipy.signal.bessel(norm="delay")``, bilinear at ``1/h``)."""
    from scipy.signal import bessel, bilinear

    b, a = bilinear(*bessel(2, 1.0 / delay, analog=True, norm="delay"), fs=1.0 / h)
    return lfilter(b, a, x, axis=0)


def drifting_offsets(i: np.ndarray, sensors: Sensors, dt: float) -> np.ndarray:
    """Current offsets (K, 2) of probes that warm with their own current (see module
    docstring): ``o_0 + o_d h(t)/h(T)``."""
    a = math.exp(-dt / sensors.offset_drift_tau)
    heat = lfilter([dt], [1.0, -a], i**2, axis=0)
    return np.asarray(sensors.current_offset, float) + np.asarray(sensors.offset_drift, float) * heat / heat[-1]


def first_order(x: np.ndarray, tau: float, dt: float) -> np.ndarray:
    """``x`` (sampled every ``dt`` s) through ``1/(1 + s tau)``, starting in steady state."""
    a = math.exp(-dt / tau)
    return lfilter([1 - a], [1, -a], x, zi=[a * x[0]])[0]


def gate_mean(x: np.ndarray, gate: float, dt: float) -> np.ndarray:
    """The mean of ``x`` (sampled every ``dt`` s) over the last ``gate`` s: an encoder's count
    over its gate time (its angle increment over the gate time), trapezoidal between samples;
    before a full gate has passed, the mean since the first sample (settled at rest there)."""
    n = max(int(round(gate / dt)), 1)
    angle = np.concatenate([[0.0], np.cumsum(0.5 * (x[1:] + x[:-1]))]) * dt
    out = np.empty_like(x, dtype=float)
    out[n:] = (angle[n:] - angle[:-n]) / (n * dt)
    k = np.arange(1, min(n, len(x)))
    out[k] = angle[k] / (k * dt)
    out[0] = x[0]
    return out


def _lowpass(x: np.ndarray, fc: float, h: float) -> np.ndarray:
    if fc <= 0:
        return x
    a = math.exp(-2 * math.pi * fc * h)
    return lfilter([1 - a], [1, -a], x, axis=0, zi=np.zeros((1,) + x.shape[1:]) if x.ndim > 1 else [0.0])[0]


def _pick(x: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Rows ``idx`` of ``x``; negative indices read the rest state (row 0)."""
    return x[np.maximum(idx, 0)]


def _quantise(x: np.ndarray, q: float) -> np.ndarray:
    return np.round(x / q) * q if q > 0 else x


def ar1(rng: np.random.Generator, std: float, pole: float, shape) -> np.ndarray:
    """Stationary AR(1) noise of standard deviation ``std`` along axis 0."""
    w = rng.standard_normal(shape)
    w[0] /= math.sqrt(1 - pole**2)
    return std * math.sqrt(1 - pole**2) * lfilter([1.0], [1.0, -pole], w, axis=0)


def sensed_speed(w: np.ndarray, theta: np.ndarray, sensors: Sensors, noise: Noise, rng, dt: float = 0.0) -> np.ndarray:
    """Tachometer reading of the true speed ``w`` (rad/s, sampled every ``dt`` s) at shaft angle
    ``theta`` (rad)."""
    if sensors.speed_lag:
        w = first_order(w, sensors.speed_lag, dt)
    if sensors.speed_window:
        w = gate_mean(w, sensors.speed_window, dt)
    y = sensors.speed_gain * w + sensors.speed_offset
    if sensors.speed_ripple_rel:
        y = y + sensors.speed_ripple_rel * w * np.sin(theta + sensors.speed_ripple_phase)
    if noise.speed_ripple:
        y = y + noise.speed_ripple * np.sin(noise.ripple_order * theta)
    if noise.speed_white:
        y = y + rng.normal(0.0, noise.speed_white, len(y))
    return _quantise(y, noise.speed_quantum)


def startup_record(out: np.ndarray, cols: dict, v_step: np.ndarray, zoh: bool, K: int, M: int, h: float,
                   sensors: Sensors, noise: Noise, rng: np.random.Generator, measured_voltage: bool) -> dict:
    """The recorded start-up columns (``t, v_r, v_s, v_t, i_r, i_s`` [, ``speed``][, ``torque``]).

    ``out`` is the trajectory (rows per internal step, columns ``cols``), ``v_step`` (n, 2)
    the alpha-beta voltage per step (switch-state average for inverters, terminal value at
    the step start for the grid), ``zoh`` whether a sample holds the mean over its steps.
    """
    base = np.arange(K) * M
    cur = _lowpass(out[:, [cols["i_a"], cols["i_b"]]], sensors.anti_alias, h)
    if sensors.current_filter_delay:
        cur = bessel_delay(cur, sensors.current_filter_delay, h)
    if sensors.current_delays:  # a multiplexed card: each phase at its own instant
        phases = inverse_clarke(cur[:, 0], cur[:, 1])
        i3 = np.column_stack([_pick(phases[:, k], base - d) for k, d in enumerate(sensors.current_delays)])
    else:
        i_ab = _pick(cur, base - sensors.current_delay)
        i3 = inverse_clarke(i_ab[:, 0], i_ab[:, 1])[:, :2]
    if zoh:
        vpad = np.vstack([np.zeros((M + sensors.voltage_delay, 2)), v_step])
        csum = np.vstack([np.zeros((1, 2)), np.cumsum(vpad, axis=0)])
        start = base - sensors.voltage_delay + M + sensors.voltage_delay
        v_ab = (csum[start + M] - csum[start]) / M
    elif sensors.voltage_delays:
        v_int = _lowpass(v_step, sensors.anti_alias, h)
        phases = inverse_clarke(v_int[:, 0], v_int[:, 1])
        v_ab = None
        v3 = np.column_stack([_pick(phases[:, k], base - d) for k, d in enumerate(sensors.voltage_delays)])
    else:
        v_ab = _pick(_lowpass(v_step, sensors.anti_alias, h), base - sensors.voltage_delay)
    rec = {"t": np.arange(K) * (M * h)}
    if v_ab is not None:
        v3 = inverse_clarke(v_ab[:, 0], v_ab[:, 1])
    v3 = v3 + np.asarray(sensors.voltage_offset, float)
    if measured_voltage:
        if noise.voltage_white:
            v3 = v3 + rng.normal(0.0, noise.voltage_white, v3.shape)
        v3 = _quantise(v3, noise.voltage_quantum)
    offsets = drifting_offsets(i3, sensors, M * h) if any(sensors.offset_drift) else sensors.current_offset
    i3 = probe_reading(i3, sensors, M * h) + np.asarray(offsets, float)
    if noise.current_white:
        i3 = i3 + rng.normal(0.0, noise.current_white, i3.shape)
    if noise.current_colored:
        i3 = i3 + ar1(rng, noise.current_colored, noise.current_pole, i3.shape)
    i3 = _quantise(i3, noise.current_quantum)
    if sensors.compress == "clip":
        i3 = np.clip(i3, -sensors.compress_level, sensors.compress_level)
    rec.update(v_r=v3[:, 0], v_s=v3[:, 1], v_t=v3[:, 2], i_r=i3[:, 0], i_s=i3[:, 1])
    if sensors.has_speed:
        w = _pick(_lowpass(out[:, cols["w_l"]], sensors.anti_alias, h), base)
        rec["speed"] = sensed_speed(w, _pick(out[:, cols["theta"]], base), sensors, noise, rng, M * h)
    if sensors.has_torque:
        tq = _pick(out[:, cols["T_sh"]], base)
        rec["torque"] = tq + (rng.normal(0.0, noise.torque_white, K) if noise.torque_white else 0.0)
    return rec

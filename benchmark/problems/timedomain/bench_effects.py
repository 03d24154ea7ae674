"""Time-domain effects that real bench records bring: sensors and shaft (the load on the shaft:
:mod:`benchmark.problems.timedomain.load_effect`; channel offsets:
:mod:`benchmark.problems.timedomain.offset_effect`).

Each is a plant (:meth:`plant` on an extended-model row, or :meth:`plant_extras` with
:meth:`measure` for what the sensors do to the record) and an augmentation
(:meth:`extra_bounds`, :meth:`extra_starts`, :meth:`augment` and/or :meth:`measure`). Sizes,
units and realistic ranges (the YAML defaults in ``conf/effect/``):

``current_sensor_saturation``
    Phase-current probes compress softly or clip at the acquisition range. Size: the probe's
    level over the start-up current peak of the undisturbed record, 0.3-0.6 (1.5-3 times rated
    current for a start-up peak of 5 times rated). Forms ``kind``: ``tanh`` ``L tanh(i/L)``,
    ``knee`` (linear to ``L``, then ``L + w tanh((|i| - L)/w)``, ``w = L/2``), ``clip`` (hard
    clipping at ``L``); ``probes``: 2 (line currents of R and S measured, T from the zero sum:
    the common bench) or 3. Augmentation: ``f(i) = i / (1 + (|i|/L)^n)^(1/n)`` on each probed
    phase, then back to alpha-beta; extras ``cs_level`` (``L`` over the recorded current peak)
    and ``cs_sharpness`` ``n`` (about 2.5 matches ``tanh``, 8-15 a knee, 30+ a clip).
``speed_sensor_gain``
    Tachometer ``(1 + g) w + w_0`` (the plant), fitted as ``(1 + g + a sin(theta) + b cos(theta))
    w + w_0`` with a ripple once per revolution of the shaft angle ``theta`` (real tachometers
    have one). Its output filter is a fact of the instrument, not fitted: every model reads its
    speed through the filter ``meta.yaml`` states (``speed_filter``,
    :mod:`~benchmark.problems.timedomain.speed_filter`). Size: ``|g|``, 0.01-0.05; forms:
    ``sign`` of ``g``, ``offset`` ``w_0`` as a fraction of synchronous speed (within +-0.005).
    Extras ``tach_gain_error`` (fraction), ``tach_offset`` (fraction of synchronous speed),
    ``tach_ripple_sin``, ``tach_ripple_cos``. Excluded when the record has no speed channel.
``two_mass``
    Motor and load inertias coupled by a torsional spring and damper, speed sensed on the load
    side. Size: the resonance ``sqrt(k (1/J_m + 1/J_l))/2 pi``, 30-200 Hz; forms
    ``inertia_ratio`` ``J_l/J_m`` 0.3-2, ``damping_ratio`` 0.02-0.1. The base model's ``J`` is the
    total inertia (what a rigid-shaft fit sees); extras ``tm_freq`` (Hz), ``tm_ratio``,
    ``tm_zeta``, ``tm_backlash`` (rad, the free play's half-width) and ``tm_hardening`` (an
    elastomer coupling's stiffness at the torque scale's twist over its small-twist stiffness,
    1-5; 1: a linear spring).
``channel_delay``
    A time skew between the voltage and current channels. Size: 0.1-2 samples; form ``lag``:
    ``current`` (the current channels lag) or ``voltage``. Augmentation: the simulated currents
    delayed by ``skew`` samples (signed: positive = currents lag) by cubic (4-point Lagrange)
    interpolation; extra ``skew`` (samples), searched about the skew ``meta.yaml`` states
    (``channel_skew``); a candidate only where it states one (:class:`ChannelDelay`).
"""

from __future__ import annotations

import math

import numpy as np

from benchmark.core.effects import Effect
from benchmark.problems.timedomain.channel_timing import current_lags, delay_phase_currents, fractional_delay
from benchmark.problems.timedomain.extended import IDX

SQ3 = math.sqrt(3.0)


# ----------------------------------------------------------------------------- current probes
def compress_soft(i: np.ndarray, level: np.ndarray, n: np.ndarray) -> np.ndarray:
    """``i / (1 + (|i|/L)^n)^(1/n)`` (broadcast): linear at small current, flat at ``L``."""
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        x = np.abs(i) / level
        small = x <= 1.0
        xs = np.where(small, x, 1.0)
        xl = np.where(small, 1.0, x)
        low = i / (1.0 + xs**n) ** (1.0 / n)
        high = np.sign(i) * level / (1.0 + xl ** (-n)) ** (1.0 / n)  # no overflow for large |i|
        return np.where(small, low, high)


def compress_form(i: np.ndarray, kind: str, level: float) -> np.ndarray:
    """The plant's probe characteristics (``tanh``, ``knee``, ``clip``, ``soft``)."""
    if kind == "tanh":
        return level * np.tanh(i / level)
    if kind == "knee":
        w = 0.5 * level
        a = np.abs(i)
        return np.where(a <= level, i, np.sign(i) * (level + w * np.tanh((a - level) / w)))
    if kind == "clip":
        return np.clip(i, -level, level)
    if kind == "soft":
        return compress_soft(i, level, 4.0)
    raise ValueError(f"current_sensor_saturation: kind must be tanh, knee, clip or soft, got {kind!r}")


def _through_probes(sim: np.ndarray, fn, probes: int) -> np.ndarray:
    """Apply ``fn`` to the probed phase currents of ``sim`` (n, 3, N), back to alpha-beta."""
    out = sim.copy()
    a, b = sim[:, 0], sim[:, 1]
    r = a
    s = -0.5 * a + 0.5 * SQ3 * b
    fr, fs = fn(r), fn(s)
    if probes == 3:
        ft = fn(-0.5 * a - 0.5 * SQ3 * b)
        out[:, 0] = (2.0 / 3.0) * (fr - 0.5 * (fs + ft))
        out[:, 1] = (fs - ft) / SQ3
    else:
        out[:, 0] = fr
        out[:, 1] = (fr + 2.0 * fs) / SQ3
    return out


class CurrentSensorSaturation(Effect):
    name = "current_sensor_saturation"
    size_name = "level_over_startup_peak"
    realistic = (0.3, 0.6)
    extra_names = ("cs_level", "cs_sharpness")
    extra_units = ("p.u. of recorded current peak", "-")
    physics = "phase-current probes compress softly or clip at their range"
    shows_in = "flat-topped start-up current peaks, the same level on each phase"
    measure_stage = 1
    FORM_DRAWS = {"kind": {"choice": ["tanh", "knee", "clip"]}}

    def _probes(self, form=None) -> int:
        return int({**self.form, **(form or {})}.get("probes", 2))

    def plant(self, row, size, ctx, form=None):
        return row.copy()

    def plant_extras(self, size, ctx, form=None):
        return np.array([float(size)])

    def plant_measure(self, sim, extras, ctx, form=None):
        form = {**self.form, **(form or {})}
        level = float(extras[0]) * ctx.I_peak
        return _through_probes(sim, lambda i: compress_form(i, str(form.get("kind", "tanh")), level),
                               self._probes(form))

    def extra_bounds(self, ctx):
        return np.array([0.3, 1.0]), np.array([8.0, 60.0])

    def extra_starts(self, ctx):
        return [np.array([1.1, 3.0]), np.array([0.95, 12.0]), np.array([1.0, 40.0])]

    def measure(self, sim, extras, ctx):
        extras = np.atleast_2d(extras)
        level = (extras[:, 0] * ctx.I_peak)[:, None]
        n = extras[:, 1][:, None]
        return _through_probes(sim, lambda i: compress_soft(i, level, n), self._probes())

    def describe_fit(self, extras, ctx, base=None):
        x = np.ravel(extras)
        return {"level_A": float(x[0] * ctx.I_peak), "sharpness": float(x[1])}


# ----------------------------------------------------------------------------- tachometer
class SpeedSensorGain(Effect):
    name = "speed_sensor_gain"
    size_name = "gain_error"
    realistic = (0.01, 0.05)
    extra_names = ("tach_gain_error", "tach_offset", "tach_ripple_sin", "tach_ripple_cos")
    #: Gain and offset only: the ripple once per revolution came with d666695 (two_mass and
    #: sensor_offset had chased a plant tachometer's ripple). Its output filter is not an error
    #: of the tachometer but a fact of the instrument, read by every model where ``meta.yaml``
    #: states it (:mod:`~benchmark.problems.timedomain.speed_filter`).
    FIRST_FORM = {"tach_ripple_sin": 0.0, "tach_ripple_cos": 0.0}
    extra_units = ("p.u. of true speed", "p.u. of w_sync", "p.u. of true speed", "p.u. of true speed")
    physics = "tachometer gain error, offset and ripple at the rotation frequency"
    shows_in = "steady speed off synchronous-minus-slip; a constant ratio in the speed residual"
    measure_stage = 3
    FORM_DRAWS = {"sign": {"choice": [-1.0, 1.0]}, "offset": [-0.005, 0.005]}

    def plant(self, row, size, ctx, form=None):
        return row.copy()

    def plant_extras(self, size, ctx, form=None):
        form = {**self.form, **(form or {})}
        return np.array([float(form.get("sign", 1.0)) * float(size), float(form.get("offset", 0.0)), 0.0, 0.0])

    #: The largest offset of a tachometer (p.u. of synchronous speed) where the record does not
    #: say what it reads at rest.
    MAX_OFFSET = 0.02

    def _offset_range(self, ctx) -> tuple[float, float]:
        """The offset's range (p.u. of synchronous speed): what the channel reads while the rotor
        is at rest, within that reading's noise band (``ctx.facts["speed_reading_at_rest"]``,
        :func:`~benchmark.problems.timedomain.diagnosis.scales.speed_reading_at_rest`), else
        +-:data:`MAX_OFFSET`."""
        rest = ctx.facts.get("speed_reading_at_rest")
        if not rest or not ctx.w_sync > 0:
            return -self.MAX_OFFSET, self.MAX_OFFSET
        return (rest["mean"] - rest["band"]) / ctx.w_sync, (rest["mean"] + rest["band"]) / ctx.w_sync

    def extra_bounds(self, ctx):
        lo, hi = self._offset_range(ctx)
        return np.array([-0.1, lo, -0.05, -0.05]), np.array([0.1, hi, 0.05, 0.05])

    def extra_starts(self, ctx):
        lo, hi = self._offset_range(ctx)
        return [np.array([0.0, min(max(0.0, lo), hi), 0.0, 0.0])]

    def measure(self, sim, extras, ctx):
        """``(1 + g + a sin(theta) + b cos(theta)) w + offset w_sync``: gain, offset and a ripple
        once per revolution (an eccentric or unbalanced tachometer), ``theta`` the shaft angle
        from the start of the record (the unknown initial angle is in ``a``, ``b``: the ripple
        is linear in both, so a fit from zero is not stuck at a phase). A filter the instrument
        has comes after (:mod:`~benchmark.problems.timedomain.speed_filter`)."""
        extras = np.atleast_2d(extras)
        out = sim.copy()
        theta = np.cumsum(np.nan_to_num(sim[:, 2]), axis=1) * (ctx.sample_time or 1.0)
        w = sim[:, 2]
        ripple = extras[:, 2:3] * np.sin(theta) + extras[:, 3:4] * np.cos(theta)
        out[:, 2] = w * (1.0 + extras[:, 0:1] + ripple) + extras[:, 1:2] * ctx.w_sync
        return out

    def measure_stop(self, w, extras, ctx, t, measured):
        """The same tachometer on the free stop: gain and offset as on the start-up, the ripple
        with the start-up's amplitude ``hypot(a, b)`` and its phase profiled out (the stop
        record's shaft angle at its start is unknown: the phase is the one that fits
        ``measured`` best, in closed form, for each candidate)."""
        extras = np.atleast_2d(extras)
        dt = float(np.median(np.diff(t))) if len(t) > 1 else 0.0
        theta = np.cumsum(np.nan_to_num(w), axis=1) * dt
        base = w * (1.0 + extras[:, 0:1]) + extras[:, 1:2] * ctx.w_sync
        sw, cw = w * np.sin(theta), w * np.cos(theta)
        with np.errstate(all="ignore"):
            r0 = np.nan_to_num(np.asarray(measured, float)[None, :] - base)
            S = np.sum(r0 * np.nan_to_num(sw), axis=1, keepdims=True)
            C = np.sum(r0 * np.nan_to_num(cw), axis=1, keepdims=True)
            norm = np.hypot(S, C)
            cos_psi = np.where(norm > 0, S / np.where(norm > 0, norm, 1.0), 1.0)
            sin_psi = np.where(norm > 0, C / np.where(norm > 0, norm, 1.0), 0.0)
        rho = np.hypot(extras[:, 2:3], extras[:, 3:4])
        return base + rho * (cos_psi * sw + sin_psi * cw)

    def stop_true_speed(self, w, extras, ctx):
        extras = np.atleast_2d(extras)
        return (w - extras[:, 1:2] * ctx.w_sync) / (1.0 + extras[:, 0:1])

    def applies_to(self, facts):
        if not facts.get("has_speed", True):
            return "the record has no speed channel"
        return None

    def fitted_size(self, extras, ctx):
        """The largest of the tachometer's errors as a fraction of the speed: gain error, offset
        (of synchronous speed) and ripple."""
        x = np.ravel(extras)
        return float(max(abs(x[0]), abs(x[1]), math.hypot(x[2], x[3])))

    def describe_fit(self, extras, ctx, base=None):
        x = np.ravel(extras)
        return {"gain": float(1.0 + x[0]), "offset_rad_s": float(x[1] * ctx.w_sync),
                "ripple_per_revolution": float(np.hypot(x[2], x[3]))}


# ----------------------------------------------------------------------------- shaft
class TwoMass(Effect):
    name = "two_mass"
    size_name = "resonance"
    size_unit = "Hz"
    realistic = (30.0, 200.0)
    extra_names = ("tm_freq", "tm_ratio", "tm_zeta", "tm_backlash", "tm_hardening")
    #: A linear spring and damper: the free play came with 0865c78 (7 of 10 plant couplings had
    #: one), the hardening with 8ca8136 (held-out ``elastomer``: beside its linear spring a load
    #: or a leakage saturation took what the coupling left, motulator seed 407).
    FIRST_FORM = {"tm_backlash": 0.0, "tm_hardening": 1.0}
    extra_units = ("Hz", "p.u. of motor inertia", "-", "rad",
                   "stiffness at the torque scale over small-twist stiffness")
    physics = ("motor and load inertias coupled by a torsional spring and damper, with free play (backlash) and a "
               "stiffness that may rise with the twist (an elastomer jaw coupling); speed sensed on the load side")
    shows_in = "speed oscillation and plateaus in the first cycles; torque ripple passed through the coupling"
    FORM_DRAWS = {"inertia_ratio": [0.3, 2.0], "damping_ratio": [0.02, 0.1]}
    #: Largest hardening: an elastomer spider is some 2-4 times stiffer at its rated torque than
    #: at rest (a jaw coupling's dynamic stiffness over its static one at small twist).
    MAX_HARDENING = 5.0

    def plant(self, row, size, ctx, form=None):
        form = {**self.form, **(form or {})}
        x = np.array([[float(size), float(form.get("inertia_ratio", 1.0)), float(form.get("damping_ratio", 0.05)),
                       float(form.get("backlash", 0.0)), float(form.get("hardening", 1.0))]])
        return self.augment(row[None, :], x, ctx)[0]

    def _f_max(self, ctx):
        return 400.0 if not ctx.sample_time else min(400.0, 0.125 / ctx.sample_time)

    def extra_bounds(self, ctx):
        """Resonance (Hz, at small twist), J_load / J_motor, damping ratio, half-width of the free
        play (rad, up to 2 degrees; jaw and pin couplings have a few tenths of a degree), hardening
        (1: a linear spring, up to :data:`MAX_HARDENING`)."""
        return (np.array([10.0, 0.05, 0.002, 0.0, 1.0]),
                np.array([self._f_max(ctx), 5.0, 0.7, 0.035, self.MAX_HARDENING]))

    def extra_starts(self, ctx):
        fmax = self._f_max(ctx)
        # the first is the screening's; 20 Hz for soft couplings (a motulator record's 20.4 Hz was out of reach from 40)
        return [np.array([min(f, 0.9 * fmax), 1.0, 0.05, 0.0, 1.0]) for f in (40.0, 80.0, 150.0, 250.0, 20.0)]

    @staticmethod
    def cubic_term(k, hardening, ctx):
        """``k_cubic`` (1/rad^2) of a coupling of small-twist stiffness ``k`` (N m/rad) whose
        incremental stiffness ``k (1 + 3 k_cubic z^2)`` is ``hardening`` times ``k`` at the twist
        that transmits the torque scale (``ctx.torque_scale``, N m): that twist is
        ``z_n = T / (k (1 + (H - 1)/3))`` and ``k_cubic = (H - 1) / (3 z_n^2)``."""
        H = np.maximum(np.asarray(hardening, float), 1.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            z_n = ctx.torque_scale / (k * (1.0 + (H - 1.0) / 3.0))
            out = (H - 1.0) / (3.0 * z_n * z_n)
        return np.where(H > 1.0, out, 0.0)

    def augment(self, rows, extras, ctx):
        rows = rows.copy()
        f, r, z = extras[:, 0], extras[:, 1], extras[:, 2]
        J = rows[:, IDX["J"]].copy()
        J_m = J / (1.0 + r)
        J_l = J * r / (1.0 + r)
        J_r = J_m * J_l / (J_m + J_l)
        k = (2.0 * np.pi * f) ** 2 * J_r
        rows[:, IDX["J"]] = J_m
        rows[:, IDX["J_l"]] = J_l
        rows[:, IDX["k_sh"]] = k
        rows[:, IDX["c_sh"]] = 2.0 * z * np.sqrt(k * J_r)
        rows[:, IDX["backlash"]] = extras[:, 3] if extras.shape[1] > 3 else 0.0
        rows[:, IDX["k_cubic"]] = self.cubic_term(k, extras[:, 4], ctx) if extras.shape[1] > 4 else 0.0
        return rows

    def describe_fit(self, extras, ctx, base=None):
        x = np.ravel(extras)
        return {"resonance_Hz": float(x[0]), "J_load_over_J_motor": float(x[1]), "damping_ratio": float(x[2]),
                "backlash_half_width_deg": float(np.degrees(x[3])) if len(x) > 3 else 0.0,
                "stiffness_at_torque_scale_over_small_twist": float(x[4]) if len(x) > 4 else 1.0,
                "torque_scale_Nm": float(ctx.torque_scale)}


# ----------------------------------------------------------------------------- channel skew
class ChannelDelay(Effect):
    """A time skew between the voltage and current channels of the acquisition. A card samples
    its channels at once (no skew) or in a documented sequence (a known fraction of a sample,
    ``k/N`` for the ``k``-th of ``N`` multiplexed channels): the skew is a fact of the
    acquisition, stated in ``meta.yaml`` (``channel_skew``, samples, positive when the currents
    are sampled after the voltages; a number, or ``[low, high]``; or the card's sequence, a
    mapping of phase channels to their own skews, :mod:`~benchmark.problems.timedomain.channel_timing`),
    and the fit searches it within :data:`SKEW_TOLERANCE` of the stated value (within the stated
    range). For a sequence the voltage channels are realigned when the record is read and the
    two current channels keep their stated ratio: the extra ``skew`` is the larger current
    channel's, each phase current delayed by its own. A record that states none (or 0) cannot
    carry one: ``channel_delay`` is then not a candidate."""

    name = "channel_delay"
    size_name = "skew"
    size_unit = "samples"
    realistic = (0.1, 2.0)
    extra_names = ("skew",)
    extra_units = ("samples",)
    physics = "a time skew between the voltage and current channels (a multiplexed card's documented sequence)"
    shows_in = "a quadrature residual at the supply frequency"
    measure_stage = 0
    FORM_DRAWS = {"lag": {"choice": ["current", "voltage"]}}
    #: Relative tolerance of a stated skew: a multiplexed card's sequence is documented, its
    #: conversion clock and sample-and-hold aperture are known to some tens of per cent.
    SKEW_TOLERANCE = 0.25

    @staticmethod
    def sequence(facts: dict) -> np.ndarray | None:
        """A stated sequence's current skews ``(i_r, i_s)`` over the larger one (the extra
        ``skew`` scales them), or None (a number, a range, none)."""
        lags = current_lags((facts or {}).get("channel_skew"))
        if lags is None or not any(lags):
            return None
        return np.array(lags) / max(lags, key=abs)

    @staticmethod
    def stated(facts: dict) -> tuple[float, float] | None:
        """The stated skew range (samples) of ``facts`` (``channel_skew``), or None."""
        v = (facts or {}).get("channel_skew")
        if v is None:
            return None
        if isinstance(v, dict):
            lags = current_lags(v)
            v = max(lags, key=abs)
        lo, hi = (float(v[0]), float(v[1])) if np.ndim(v) else (float(v), float(v))
        if lo == hi == 0.0:
            return None
        if lo == hi:
            d = ChannelDelay.SKEW_TOLERANCE * abs(lo)
            return lo - d, hi + d
        return min(lo, hi), max(lo, hi)

    def applies_to(self, facts):
        if self.stated(facts) is None:
            return ("meta.yaml states no channel skew (channel_skew): a card that samples its channels at once "
                    "has none, a multiplexed one a documented fraction of a sample")
        return None

    def plant(self, row, size, ctx, form=None):
        return row.copy()

    def plant_extras(self, size, ctx, form=None):
        form = {**self.form, **(form or {})}
        sign = -1.0 if str(form.get("lag", "current")) == "voltage" else 1.0
        return np.array([sign * float(size)])

    def extra_bounds(self, ctx):
        lo, hi = self.stated(ctx.facts) or (-self.realistic[1], self.realistic[1])
        return np.array([lo]), np.array([hi])

    def extra_starts(self, ctx):
        lo, hi = self.extra_bounds(ctx)
        return [0.5 * (lo + hi)]

    def measure(self, sim, extras, ctx):
        extras = np.atleast_2d(extras)
        out = sim.copy()
        ratio = self.sequence(ctx.facts)
        if ratio is None:
            out[:, :2] = fractional_delay(np.ascontiguousarray(sim[:, :2]), extras[:, 0])
        else:
            out[:, :2] = delay_phase_currents(sim[:, :2], extras[:, :1] * ratio[None, :])
        return out

    def describe_fit(self, extras, ctx, base=None):
        x = float(np.ravel(extras)[0])
        out = {"skew_samples": x, "skew_s": x * ctx.sample_time}
        ratio = self.sequence(ctx.facts)
        if ratio is not None:
            out.update(i_r_skew_samples=float(x * ratio[0]), i_s_skew_samples=float(x * ratio[1]))
        return out

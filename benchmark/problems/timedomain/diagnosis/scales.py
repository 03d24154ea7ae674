"""Physical scales of the machine on a record: rated torque and current, the friction's search
range, a load the base model holds as friction, and the effects' context (step 3 of
:mod:`.pipeline`).

The numbers here are physics priors (a motor's pull-out over rated torque, its own friction, its
efficiency times power factor), each with its source in ``docs/effects.md``; none was set on a
diagnosis's verdicts.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from benchmark.core.effects import effect_context
from benchmark.problems.timedomain.conditioning import OFFSET_STANDARD_ERRORS
from benchmark.problems.timedomain.extended import base_rows
from benchmark.problems.timedomain.motor import InductionMotor

#: Share of the estimated rated torque (:func:`estimated_rated_torque`) that the local fits may
#: always give the friction, whatever the base identification says (a motor's own friction is
#: 0.3-2 % of its rated torque).
FRICTION_FLOOR_SHARE = 0.03
#: Pull-out over rated torque of the motor whose rated torque :func:`estimated_rated_torque`
#: guesses: induction motors have 2-3.5 (IEC, NEMA design B; the validation motors 2.3-4.9).
PULLOUT_OVER_RATED = 3.0
#: Largest efficiency times power factor of an induction motor at its rated point (large
#: premium motors about 0.85; 1-7.5 kW motors 0.6-0.75): a rated power ``P`` (W) means a rated
#: current of at least ``P / (3 V_phase MAX_EFFICIENCY_POWER_FACTOR)``.
MAX_EFFICIENCY_POWER_FACTOR = 0.85


def friction_scale(estimate: dict[str, float], ctx) -> float:
    """Scale of the friction's search range (N m): 0.3 of the viscous torque at synchronous
    speed plus :data:`FRICTION_FLOOR_SHARE` of the estimated rated torque. ``fc`` is searched
    in ``[0, 5 fc + this]``, ``fv`` up to ``5 fv + this / w_sync``. The floor keeps a friction
    that the base identification put at zero free: a tachometer that reads above synchronous
    speed pulls both to zero, and a box of ``[0, 5 x 0]`` would lock them there for every
    augmented model, so that a load torque would be chosen to stand in for the motor's own
    friction."""
    return 0.3 * estimate["fv"] * ctx.w_sync + FRICTION_FLOOR_SHARE * estimated_rated_torque(estimate, ctx) + 1e-9


def rated_torque(nameplate: dict | None) -> float | None:
    """Rated torque (N m) of a nameplate with rated power (W) and speed (rpm), else None."""
    if not nameplate or not nameplate.get("rated_power") or not nameplate.get("speed"):
        return None
    return float(nameplate["rated_power"]) / (float(nameplate["speed"]) * 2.0 * np.pi / 60.0)


def pullout_torque(Rs: float, Le: float, ctx) -> float:
    """The base model's pull-out (breakdown) torque at the record's final supply, N m:
    ``3 p V1^2 / (4 w_e (Rs + sqrt(Rs^2 + (w_e Le)^2)))`` with ``V1`` the fundamental phase
    voltage amplitude (V), ``w_e`` its angular frequency (rad/s), ``Rs`` (ohm) and the leakage
    ``Le`` (H); the magnetising branch is neglected (it lowers the torque by a few per cent)."""
    w_e = float(ctx.w_e)
    if w_e <= 0 or ctx.V1 <= 0:
        return 0.0
    return 3.0 * ctx.pole_pairs * ctx.V1**2 / (4.0 * w_e * (Rs + np.hypot(Rs, w_e * Le)))


def estimated_rated_torque(params: Mapping[str, float], ctx) -> float:
    """A rated torque (N m) for a record without a nameplate: the pull-out torque of the base
    model ``params`` over :data:`PULLOUT_OVER_RATED`; 0 when it has no ``Rs`` and ``Le``. It is
    within 0.75-1.6 times the rated torque of the validation motors, whatever their start (a
    slow inverter ramp makes ``T_acc`` a fraction of the rated torque)."""
    if "Rs" not in params or "Le" not in params:
        return 0.0
    return pullout_torque(float(params["Rs"]), float(params["Le"]), ctx) / PULLOUT_OVER_RATED


def rated_current(nameplate: dict | None, ctx, T_rated: float) -> float:
    """A rated current (A rms) no larger than the motor's: the nameplate's current; else its
    rated power, or the estimated rated torque ``T_rated`` (N m) at synchronous speed, over
    ``3 V_phase`` (the record's fundamental, rms) and :data:`MAX_EFFICIENCY_POWER_FACTOR`;
    0 when none is known."""
    plate = nameplate or {}
    if plate.get("current"):
        return float(plate["current"])
    power = float(plate.get("rated_power") or T_rated * ctx.w_sync)
    v_phase = ctx.V1 / np.sqrt(2.0)
    if power <= 0 or v_phase <= 0:
        return 0.0
    return power / (3.0 * v_phase * MAX_EFFICIENCY_POWER_FACTOR)


def held_by_base(names: list[str], x: np.ndarray, ctx, settings, rated: float | None = None,
                 standard_errors: np.ndarray | None = None) -> list[dict]:
    """Effects the base model already holds under another name: a Coulomb friction above
    ``settings.load_friction_share`` of the rated torque ``rated`` (N m, from the nameplate),
    or without one of :func:`estimated_rated_torque`, is a constant (passive) load torque.

    With ``standard_errors`` (of ``x``, N m for ``fc``) the friction must exceed the share by
    ``settings.band_k`` standard errors: without a stop record the start-up alone leaves the
    friction loosely determined (it trades with the inertia, an iron loss, the heating), and a
    friction that could be the motor's own is not called a load."""
    if rated:
        scale, label = rated, "rated torque"
    else:
        scale = estimated_rated_torque(dict(zip(names, map(float, x), strict=True)), ctx)
        label = "rated torque estimated as 1/3 of the pull-out torque"
    if "fc" not in names or not scale or scale <= 0:
        return []
    k = names.index("fc")
    fc = float(x[k])
    se = float(standard_errors[k]) if standard_errors is not None else 0.0
    se = se if np.isfinite(se) else fc  # not determined: as uncertain as it is large
    share = fc / scale
    if (fc - settings.band_k * se) / scale <= settings.load_friction_share:
        return []
    return [{"effect": "load_torque", "form": "constant", "torque_Nm": fc, "standard_error_Nm": se,
             "share_of_scale": share, "scale": label,
             "why": f"the base model's Coulomb friction, {fc:.4g} +- {se:.2g} N m, is {100 * share:.0f} % of the "
                    f"{label} {scale:.4g} N m (a motor's own friction is 0.3-2 % of rated torque): a "
                    f"constant load torque, which acts as Coulomb friction does and cannot be told "
                    f"apart from it on this record"}]


def speed_reading_at_rest(data, estimate: dict[str, float]) -> dict | None:
    """What the speed channel reads while the rotor is still at rest, in rad/s: ``{"mean",
    "band", "samples"}``, or None without a speed channel. The model starts every record from
    rest; the rotor is still there, to within what the sensor resolves, for the leading samples
    at which the base model's simulated speed stays within the channel's noise band
    (``OFFSET_STANDARD_ERRORS`` times its noise estimate; at least the first sample, the
    switch-on itself). A sensor's offset is what it reads there: within ``band``, the noise band
    of one reading plus the largest simulated speed over those samples, of their ``mean`` (one
    reading's band, not the mean's standard error: a quantised channel reads the same level at
    rest whatever offset lies inside its quantum); None where that band is 0 (a noise-free channel
    at an exact rest gives no range a fit can search). A tachometer whose offset the fits could
    set elsewhere took a load's leftover as a speed error (motulator, held-out seed 419 set 16:
    an eddy-current brake read as an offset of 0.019 of synchronous speed, at its bound, on a
    record whose first 33 samples read 0 in steps of 0.5 rad/s)."""
    if not data.has_speed:
        return None
    theta = InductionMotor.from_dict(estimate).vector()[None, :]
    simulated = data.kernel.simulate(base_rows(theta, data.pole_pairs))[0, 2]
    band = OFFSET_STANDARD_ERRORS * float(data.noise["speed"].std)
    moving = np.flatnonzero(~(np.abs(np.nan_to_num(simulated, nan=np.inf)) <= band))
    m = max(1, int(moving[0]) if len(moving) else len(simulated))
    readings = np.asarray(data.meas[2][:m], float)
    readings = readings[np.isfinite(readings)]
    band += float(np.max(np.abs(simulated[:m])))
    if not len(readings) or not (np.isfinite(band) and band > 0):  # a noise-free channel: no range to give
        return None
    return {"mean": float(np.mean(readings)), "band": band, "samples": int(len(readings))}


def base_context(data, estimate: dict[str, float], dc_link_voltage: float | None, nameplate: dict | None = None,
                 facts: dict | None = None):
    """The effects' reference scales from the record and the base estimate: the rated torque
    (the nameplate's, else :func:`estimated_rated_torque`), a rated current
    (:func:`rated_current`) and the experiment's ``facts``."""
    ctx = effect_context(data.t, data.v_alpha, data.v_beta, data.meas[0], data.meas[1],
                         data.meas[2] if data.has_speed else None,
                         data.pole_pairs, estimate["J"], estimate["Ls"] - estimate["Le"], estimate["Le"],
                         dc_link_voltage)
    T_rated = estimated_rated_torque(estimate, ctx)
    ctx = replace(ctx, T_rated=T_rated, facts=dict(facts or {}))
    return replace(ctx, I_rated=rated_current(nameplate, ctx, rated_torque(nameplate) or T_rated))

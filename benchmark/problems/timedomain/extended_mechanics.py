"""The mechanical side's laws of the extended model's kernel (:mod:`.extended`): the load
torques (a passive Coulomb-like part, a fan's quadratic part, the switched load's envelope and its
speed share: a DC generator's armature lag, an eddy-current brake's law), a coupling's torque
with free play and hardening, and the Coulomb friction at standstill. Pure functions of a row
``c`` (the format of :mod:`.extended_rows`) and the state, inlined into the stepper; torques in
N m, speeds in rad/s, times in s.

numba's on-disk cache is keyed by the source file of each function and a caller's cached code
holds its callees' code: after editing this file, touch :mod:`.extended` too.
"""

from __future__ import annotations

import math

from benchmark.problems.timedomain.compiled import compiled


@compiled(_nrt=False, inline="always")
def _armature(c):
    """True when the switched load has a part that follows speed through an armature circuit
    (``T_s`` on, a speed share and a time constant ``tau_s`` > 0): its lagged speed is a state."""
    return c[28] != 0.0 and c[41] != 0.0 and c[42] > 0.0

@compiled(_nrt=False, inline="always")
def _loads(c, env, w_mech, w_lag):
    """(passive Coulomb-like load torque, speed-dependent load torque), N m, at a time when the
    switched load's envelope is ``env`` (:func:`_envelope`). ``w_lag``: the load speed through
    the armature's first-order lag over ``w_ref`` (the state :func:`_armature` rows carry; a DC
    generator's current follows its EMF with ``L_a/R_a``), the speed share's drive there."""
    t_pass = c[25]
    t_dyn = 0.0
    if c[26] != 0.0:
        q = w_mech / c[27]
        t_dyn = c[26] * q * abs(q)
    T_s = c[28]
    if T_s != 0.0:
        share = c[41]
        t_pass += T_s * env * (1.0 - share)
        u = w_lag if _armature(c) else w_mech / c[27]
        t_dyn += T_s * env * share * _brake_law(u, c[45])
    return t_pass, t_dyn

@compiled(_nrt=False, inline="always")
def _brake_law(u, r):
    """The switched load's speed share at speed ``u`` over ``w_ref``: ``u`` (a DC generator on
    its resistor, ``r = 0``), or an eddy-current brake's ``u (1 + r^2) / (1 + (r u)^2)`` with
    ``r`` = ``w_ref`` over its critical speed (Wouterse's law, 1 at ``w_ref``, its peak at the
    critical speed)."""
    if r == 0.0:
        return u
    ru = r * u
    return u * (1.0 + r * r) / (1.0 + ru * ru)

@compiled(_nrt=False, inline="always")
def _envelope(c, t):
    """The switched load's envelope (0-1, :func:`_switched`) of row ``c`` at time ``t`` (s); 0
    where the row has no switched load (its envelope is then never read). The stepper computes
    it once per distinct time of a step (the RK4 stages at the middle share one) and hands it
    to :func:`_derivative` and :func:`_stick`."""
    if c[28] == 0.0:
        return 0.0
    return _switched(t, c[29], c[30], c[42], c[43])

@compiled(_nrt=False, inline="always")
def _switched(t, t_on, t_rise, tau, t_off):
    """Envelope (0-1) of the switched load at time t: on at ``t_on`` over a first-order rise of
    time constant ``tau`` (an armature circuit), off again at ``t_off`` (when after ``t_on``)
    with the same time constant; with ``tau = 0`` the smooth step ``0.5 (1 + tanh((t -
    t_on)/t_rise))`` (``t_rise = 0``: a hard step), never off."""
    if tau <= 0.0:
        if t_rise > 0.0:
            return 0.5 * (1.0 + math.tanh((t - t_on) / t_rise))
        return 1.0 if t >= t_on else 0.0
    if t < t_on:
        return 0.0
    if t_off > t_on and t >= t_off:
        return (1.0 - math.exp(-(t_off - t_on) / tau)) * math.exp(-(t - t_off) / tau)
    return 1.0 - math.exp(-(t - t_on) / tau)

@compiled(_nrt=False, inline="always")
def _coupling_torque(twist, slip_speed, k, c, half_play, k_cubic):
    """Torque (N m) through a coupling of stiffness ``k`` (N m/rad) and damping ``c`` (N m s/rad)
    twisted by ``twist`` (rad) at ``slip_speed`` (rad/s), with free play of half-width
    ``half_play`` (rad): nothing passes within the play, the spring and damper act in contact.
    A hardening (elastomer) coupling, ``k_cubic`` > 0 (1/rad^2): the spring's torque is
    ``k z (1 + k_cubic z^2)`` on the contact twist ``z``, its incremental stiffness
    ``k (1 + 3 k_cubic z^2)``, and the damping follows the stiffness's square root (a constant
    damping ratio: the material's loss factor)."""
    if half_play <= 0.0:
        z = twist
    elif twist > half_play:
        z = twist - half_play
    elif twist < -half_play:
        z = twist + half_play
    else:
        return 0.0
    if k_cubic > 0.0:
        q = k_cubic * z * z
        return k * z * (1.0 + q) + c * math.sqrt(1.0 + 3.0 * q) * slip_speed
    return k * z + c * slip_speed

@compiled(_nrt=False, inline="always")
def _resist(direction, drive, tc):
    """Coulomb torque: against the motion, or at standstill the drive clipped to +-tc."""
    if direction != 0.0:
        return tc * direction
    if drive > tc:
        return tc
    if drive < -tc:
        return -tc
    return drive

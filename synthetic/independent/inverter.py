"""Two-level voltage-source inverter with device drops and dead time.

Each phase leg connects its terminal to the DC rail ``+Ed`` (upper device) or ``0`` (lower).
With the phase current ``i`` (positive out of the leg) the conducting device is:

    gate on,  i > 0: upper IGBT     pole = Ed - (V_T + r i)
    gate on,  i < 0: upper diode    pole = Ed + (V_D + r |i|)
    gate off, i > 0: lower diode    pole = -(V_D + r i)
    gate off, i < 0: lower IGBT     pole = V_T + r |i|

During the dead time ``t_d`` after every gate edge both gates are off and the current's sign
decides (lower diode for ``i > 0``, upper diode for ``i < 0``): a rising edge loses
``Ed t_d`` volt-seconds when ``i > 0``, a falling edge gains them when ``i < 0``. The sign is
smoothed, ``tanh(i / i_knee)``, as a diode's exponential characteristic does near zero current.

Held-out form (``i_transition > 0``): the switching node's capacitance ``C`` (device output
capacitances, snubbers, cable) makes the transition during the dead time current-dependent
(Murai, Watanabe, Iwasaki, IEEE Trans. Ind. Appl. 23(5), 1987). At a rising edge a current
out of the leg (``i >= 0``) holds the node on the lower diode, the full ``Ed t_d`` is lost; a
current into the leg charges the node to ``Ed`` in ``t_s = 2 C Ed/|i|``: the loss is
``Ed t_d g``, ``g = 1 - x/2`` for ``x = |i|/i_c < 1`` (the node reaches only part of ``Ed`` by
the end of the dead time, then the upper device closes) and ``g = 1/(2x)`` beyond, with the
transition current ``i_c = 2 C Ed/t_d``; a falling edge mirrors it. So the dead-time error
grows smoothly through zero current instead of changing sign there.

The integrator holds the pole voltages constant over each internal step (their exact
volt-second average over the step for the gate pattern, with the current at the step start);
phase voltages of the star-connected motor are the pole voltages less their mean, so only
the alpha-beta part matters. The recorded voltages of an inverter-fed test are the ideal
switch-state voltages ``Ed (a_k - mean(a))``: what a bench computes from the gate signals.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

I_ED, I_VT, I_VD, I_R, I_TD, I_KNEE, I_CAP = range(7)
N_INVERTER = 7
SQRT3_2 = math.sqrt(3.0) / 2.0


@dataclass(frozen=True)
class Inverter:
    """Inverter non-idealities (all zero = ideal switches).

    Parameters
    ----------
    V_T : IGBT threshold voltage, V.
    V_D : diode threshold voltage, V.
    r : on-state slope resistance (both devices), ohm.
    dead_time : dead time after each gate edge, s.
    i_knee : current scale of the smoothed sign, A.
    i_transition : held-out form: the transition current ``2 C Ed/t_d`` of a capacitive
        switching node, A (0 = the diode model above).
    """

    V_T: float = 0.0
    V_D: float = 0.0
    r: float = 0.0
    dead_time: float = 0.0
    i_knee: float = 0.05
    i_transition: float = 0.0

    @property
    def ideal(self) -> bool:
        return self.V_T == 0 and self.V_D == 0 and self.r == 0 and self.dead_time == 0

    def pack(self, Ed: float) -> np.ndarray:
        return np.array([Ed, self.V_T, self.V_D, self.r, self.dead_time, self.i_knee, self.i_transition], float)


@njit(cache=True)
def transition_share(i, i_c):
    """Share ``g`` of the full dead-time loss ``Ed t_d`` at a rising edge with phase current
    ``i`` (A) through a capacitive node of transition current ``i_c`` (A); a falling edge's
    gain is ``g(-i)``."""
    if i >= 0.0:
        return 1.0
    x = -i / i_c
    return 1.0 - 0.5 * x if x < 1.0 else 0.5 / x


@njit(cache=True)
def phase_currents(ia, ib):
    """Phase currents R, S, T of a star without neutral from alpha-beta (amplitude-invariant)."""
    return ia, -0.5 * ia + SQRT3_2 * ib, -0.5 * ia - SQRT3_2 * ib


@njit(cache=True)
def clarke(xr, xs, xt):
    """Amplitude-invariant Clarke transform: ``x_a = 2/3 (x_R - (x_S + x_T)/2)``,
    ``x_b = (x_S - x_T)/sqrt(3)``."""
    return (2.0 / 3.0) * (xr - 0.5 * (xs + xt)), (xs - xt) / math.sqrt(3.0)


@njit(cache=True)
def applied_voltage(u, nr, nf, ia, ib, prm, h):
    """Alpha-beta voltage (V) applied over one internal step of length ``h`` (s).

    ``u[k]`` on-fraction of phase k's upper gate in the step, ``nr[k]``/``nf[k]`` number of
    rising/falling gate edges in it, ``(ia, ib)`` the current at the step start.
    """
    Ed = prm[I_ED]
    i3 = phase_currents(ia, ib)
    v = np.empty(3)
    for k in range(3):
        i = i3[k]
        s = math.tanh(i / prm[I_KNEE]) if prm[I_KNEE] > 0.0 else (1.0 if i > 0.0 else (-1.0 if i < 0.0 else 0.0))
        sp = 0.5 * (1.0 + s)
        sm = 0.5 * (1.0 - s)
        on = u[k]
        drop = on * (-sp * prm[I_VT] + sm * prm[I_VD]) + (1.0 - on) * (-sp * prm[I_VD] + sm * prm[I_VT]) - prm[I_R] * i
        if prm[I_CAP] > 0.0:
            dead = Ed * prm[I_TD] / h * (-nr[k] * transition_share(i, prm[I_CAP])
                                         + nf[k] * transition_share(-i, prm[I_CAP]))
        else:
            dead = Ed * prm[I_TD] / h * (-nr[k] * sp + nf[k] * sm)
        v[k] = Ed * on + drop + dead
    return clarke(v[0], v[1], v[2])

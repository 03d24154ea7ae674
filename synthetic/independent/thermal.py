"""Winding temperature: lumped thermal bodies heated by the copper losses.

``C dtheta/dt = P_loss - K (theta - theta_a)`` for one body (stator and rotor windings share
one temperature) or two (stator and rotor each with its own ``C``, ``K``). Held-out form
``three_body``: the stator winding exchanges heat with the stator core through the slot
insulation (conductance ``G``, time constant ``C_s/G`` of seconds) and the core with the
ambient, a third-order Cauer network (the lumped-parameter thermal network of e.g. Mellor,
Roberts, Turner, IEE Proc. B 138(5), 1991, cut to its three largest bodies):

    C_s dtheta_s/dt = P_s - G (theta_s - theta_c)
    C_c dtheta_c/dt = G (theta_s - theta_c) - K_c (theta_c - theta_a)
    C_r dtheta_r/dt = P_r - K_r (theta_r - theta_a)

Resistances follow the temperature: ``R(theta) = R_ref (k + theta)/(k + theta_ref)`` with
``k = 234.5`` for the copper stator winding and ``k = 228`` for the die-cast aluminium cage
(both deg C).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

K_COPPER = 234.5
K_ALUMINIUM = 228.0
T_AMB, T_INVCS, T_KS, T_INVCR, T_KR, T_ONE, T_KCU, T_KAL, T_REF, T_INVCC, T_G, T_KC = range(12)


@dataclass(frozen=True)
class Thermal:
    """Thermal model; disabled (constant temperature ``theta_ref``) when ``C_s`` is infinite.

    Parameters
    ----------
    C_s : heat capacity of the stator winding (or of the single body), J/K.
    K_s : its thermal conductance to ambient, W/K.
    C_r, K_r : the same for the rotor cage (two bodies only), J/K and W/K.
    two_body : stator and rotor separately.
    theta_ambient : ambient temperature, deg C.
    theta_start : winding temperature at t = 0, deg C (None = the machine's ``theta_ref``).
    C_c, G, K_c : ``three_body``: the stator core's heat capacity (J/K), the winding-to-core
        conductance (W/K; 0 = no core body) and the core's conductance to ambient (W/K).
    """

    C_s: float = float("inf")
    K_s: float = 0.0
    C_r: float = float("inf")
    K_r: float = 0.0
    two_body: bool = False
    theta_ambient: float = 20.0
    theta_start: float | None = None
    C_c: float = float("inf")
    G: float = 0.0
    K_c: float = 0.0

    @classmethod
    def sized(cls, two_body: bool, E_s: float, E_r: float, rise: float, rotor_factor: float, tau: float,
              theta_ambient: float, core: tuple | None = None) -> Thermal:
        """Heat capacities that make the copper energies ``E_s``, ``E_r`` (J) of the test
        raise the stator winding by ``rise`` K (the rotor by ``rotor_factor`` times that, two
        bodies); conductances for the cooling time constant ``tau`` (s).

        ``core = (tau_wc, core_ratio)``: three bodies, the winding's heat flowing into a core
        of ``core_ratio`` times its capacity with the time constant ``tau_wc`` (s); ``E_s``
        is then the stator copper energy weighted by ``exp(-(T - t)/tau_wc)`` (``T`` the end
        of the record), which gives the winding's rise at ``T`` while the core stays cool."""
        if core is not None:
            tau_wc, ratio = core
            Cs, Cr = E_s / rise, E_r / (rise * rotor_factor)
            return cls(C_s=Cs, K_s=0.0, C_r=Cr, K_r=Cr / tau, two_body=True, theta_ambient=theta_ambient,
                       C_c=ratio * Cs, G=Cs / tau_wc, K_c=ratio * Cs / tau)
        if not two_body:
            C = (E_s + E_r) / rise
            return cls(C_s=C, K_s=C / tau, theta_ambient=theta_ambient)
        Cs = E_s / rise
        Cr = E_r / (rise * rotor_factor)
        return cls(C_s=Cs, K_s=Cs / tau, C_r=Cr, K_r=Cr / tau, two_body=True, theta_ambient=theta_ambient)

    @property
    def enabled(self) -> bool:
        return bool(np.isfinite(self.C_s))

    def pack(self, theta_ref: float) -> np.ndarray:
        out = np.zeros(12)
        out[T_AMB] = self.theta_ambient
        out[T_INVCS] = 1.0 / self.C_s if np.isfinite(self.C_s) else 0.0
        out[T_KS] = self.K_s
        out[T_INVCR] = 1.0 / self.C_r if np.isfinite(self.C_r) else 0.0
        out[T_KR] = self.K_r
        out[T_ONE] = 0.0 if self.two_body else 1.0
        out[T_KCU], out[T_KAL], out[T_REF] = K_COPPER, K_ALUMINIUM, theta_ref
        if self.G > 0:
            out[T_INVCC], out[T_G], out[T_KC] = 1.0 / self.C_c, self.G, self.K_c
        return out


@njit(cache=True)
def resistance_factors(theta_s, theta_r, therm):
    """(stator, rotor) resistance factors ``R(theta)/R(theta_ref)``."""
    ref = therm[T_REF]
    return ((therm[T_KCU] + theta_s) / (therm[T_KCU] + ref),
            (therm[T_KAL] + theta_r) / (therm[T_KAL] + ref))


@njit(cache=True)
def thermal_derivatives(x, b, p_stator, p_rotor, therm, dx):
    """Derivatives of ``x[b]`` (stator winding), ``x[b+1]`` (rotor) and ``x[b+2]`` (stator
    core) temperatures, K/s."""
    amb = therm[T_AMB]
    dx[b + 2] = 0.0
    if therm[T_ONE] != 0.0:
        d = therm[T_INVCS] * (p_stator + p_rotor - therm[T_KS] * (x[b] - amb))
        dx[b] = d
        dx[b + 1] = d
    elif therm[T_G] > 0.0:
        flow = therm[T_G] * (x[b] - x[b + 2])
        dx[b] = therm[T_INVCS] * (p_stator - flow)
        dx[b + 1] = therm[T_INVCR] * (p_rotor - therm[T_KR] * (x[b + 1] - amb))
        dx[b + 2] = therm[T_INVCC] * (flow - therm[T_KC] * (x[b + 2] - amb))
    else:
        dx[b] = therm[T_INVCS] * (p_stator - therm[T_KS] * (x[b] - amb))
        dx[b + 1] = therm[T_INVCR] * (p_rotor - therm[T_KR] * (x[b + 1] - amb))

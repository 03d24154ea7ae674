"""Steady-state per-phase equivalent circuit of the induction machine (Lindsay and Barton, 1972).

Conventions (stated once)
-------------------------
* Per phase, RMS phasors, SI units; impedances in ohm *at the test frequency* (reactances are
  ``X = 2*pi*f*L``). Three phases: powers carry the factor 3.
* Slip ``s = (n_sync - n)/n_sync``: motoring ``0 < s < 1``, generating ``s < 0``, braking ``s > 1``.
* Circuit (Lindsay and Barton): stator ``Z1 = R1t + jX1`` where ``R1t = R1 +
  R1sigma`` (copper plus leakage-flux core loss; at one frequency only the sum acts), series
  magnetising branch ``Z0 = R0 + jX0``, rotor
  ``Z2(s) = R2/s + R2sigma*sign(s) + j*(X2 - X3*|s|)``. The 6-parameter model is
  ``R1sigma = R2sigma = X3 = 0``.
* Input admittance ``Y = G + jB = 1/Zin``; B < 0 for the lagging machine.
* Air-gap power ``P_ag = 3*Re(E*conj(I2))`` (E the air-gap voltage), torque ``T = P_ag/w_sync``
  with ``w_sync = 2*pi*f/p`` (mechanical, rad/s). Motoring: T > 0, P_mech > 0; generating:
  P_ag < 0, T < 0, P_mech < 0 (shaft power in); braking: T > 0, P_mech < 0 and the rotor
  dissipates ``s*P_ag``, more than the air-gap power.

All functions are pure and broadcast over numpy arrays: parameters of shape ``(n_pop, 1)`` with a
slip array of shape ``(n,)`` give ``(n_pop, n)`` results. The rotor enters through its
*admittance* ``Y2 = 1/Z2``, which is finite (zero) at synchronous speed, so ``s = 0`` needs no
special case.

Why no 10-parameter model (the rotor core-loss resistances Rc1, Rc2 of the paper's Fig. 3): the
paper reports the error function to be "quite insensitive" to them, so that the optimiser could not
move them from their arbitrary starting values. A model term the data cannot determine would only
add a flat direction to every optimiser's landscape; it is left out deliberately.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace

import numpy as np

from benchmark.core.constants import COPPER_INFERRED_ZERO_C

__all__ = [
    "CircuitParameters",
    "OperatingPoint",
    "ThermalModel",
    "COPPER_INFERRED_ZERO_C",
    "slip_from_speed",
    "speed_from_slip",
    "synchronous_speed_rpm",
    "rotor_admittance",
    "input_impedance",
    "input_admittance",
    "operating_point",
    "bilinear_coefficients",
    "bilinear_to_circuit",
    "warped_slip",
    "copper_factor",
    "temperature_from_resistance",
]



@dataclass(frozen=True)
class CircuitParameters:
    """Equivalent-circuit parameters, ohm at the test frequency (per phase, referred to the stator).

    Attributes
    ----------
    R1 : float
        Stator winding (copper) resistance, ohm. Equal to the DC resistance (skin effect neglected).
    X1 : float
        Stator leakage reactance, ohm.
    R2 : float
        Rotor winding resistance referred to the stator, ohm.
    X2 : float
        Rotor leakage reactance at zero slip, ohm.
    R0 : float
        Series resistance of the magnetising branch (main-flux core loss), ohm.
    X0 : float
        Series magnetising reactance, ohm.
    R1sigma : float
        Stator leakage-flux core-loss resistance, ohm (in series with R1). 0 in the 6-parameter model.
    R2sigma : float
        Rotor leakage-flux core-loss term, ohm, entering as ``R2sigma*sign(s)``. 0 in the 6-parameter model.
    X3 : float
        Leakage saturation reactance, ohm, entering the rotor as ``-X3*|s|``. 0 in the 6-parameter model.
    """

    R1: float
    X1: float
    R2: float
    X2: float
    R0: float
    X0: float
    R1sigma: float = 0.0
    R2sigma: float = 0.0
    X3: float = 0.0

    @property
    def R1_total(self) -> float:
        """Stator series resistance the admittance sees, ``R1 + R1sigma``, ohm."""
        return self.R1 + self.R1sigma

    @property
    def is_six_parameter(self) -> bool:
        return self.R1sigma == 0.0 and self.R2sigma == 0.0 and self.X3 == 0.0

    def to_dict(self) -> dict[str, float]:
        return {k: float(v) for k, v in asdict(self).items()}

    @classmethod
    def from_mapping(cls, m) -> CircuitParameters:
        """Build from a mapping (dict, OmegaConf node) holding at least the six basic names."""
        names = [f.name for f in fields(cls)]
        unknown = [k for k in m if k not in names]
        if unknown:
            raise KeyError(f"unknown circuit parameter(s) {unknown}; known: {names}")
        return cls(**{k: float(m[k]) for k in m})

    def at_temperature(self, theta: float, theta_ref: float) -> CircuitParameters:
        """Parameters at winding temperature ``theta`` (deg C) when these are at ``theta_ref``.

        Only the copper resistances R1 and R2 follow temperature; the core-loss terms do not."""
        k = copper_factor(theta, theta_ref)
        return replace(self, R1=self.R1 * k, R2=self.R2 * k)


# ----------------------------------------------------------------------------- slip and speed


def synchronous_speed_rpm(frequency: float, pole_pairs: int) -> float:
    """Synchronous speed, rpm: ``60*f/p``."""
    return 60.0 * frequency / pole_pairs


def slip_from_speed(speed_rpm, frequency: float, pole_pairs: int):
    """Slip (per unit) from mechanical speed in rpm."""
    ns = synchronous_speed_rpm(frequency, pole_pairs)
    return (ns - np.asarray(speed_rpm, float)) / ns


def speed_from_slip(slip, frequency: float, pole_pairs: int):
    """Mechanical speed in rpm from slip (per unit)."""
    ns = synchronous_speed_rpm(frequency, pole_pairs)
    return ns * (1.0 - np.asarray(slip, float))


# ----------------------------------------------------------------------------- circuit


def rotor_admittance(s, R2, X2, R2sigma=0.0, X3=0.0):
    """Rotor branch admittance ``Y2 = 1/Z2 = s/(R2 + s*(R2sigma*sign(s) + j*(X2 - X3*|s|)))``, S.

    Zero at ``s = 0`` (the rotor carries no current at synchronous speed)."""
    s = np.asarray(s, float)
    abs_s = np.abs(s)
    return s / (R2 + s * (R2sigma * np.sign(s) + 1j * (X2 - X3 * abs_s)))


def input_impedance(s, R1t, X1, R2, X2, R0, X0, R2sigma=0.0, X3=0.0):
    """Input impedance ``Zin = Z1 + Z0 || Z2``, ohm. ``R1t`` is the stator series resistance
    ``R1 + R1sigma``."""
    Z0 = R0 + 1j * np.asarray(X0, float)
    Y2 = rotor_admittance(s, R2, X2, R2sigma, X3)
    return R1t + 1j * np.asarray(X1, float) + Z0 / (1.0 + Z0 * Y2)


def input_admittance(s, R1t, X1, R2, X2, R0, X0, R2sigma=0.0, X3=0.0):
    """Input admittance ``Y = G + jB = 1/Zin``, S."""
    return 1.0 / input_impedance(s, R1t, X1, R2, X2, R0, X0, R2sigma, X3)


@dataclass(frozen=True)
class OperatingPoint:
    """Steady-state quantities at given slips (arrays of the slip's shape), three-phase powers.

    Attributes
    ----------
    slip : per unit.  Y : input admittance, S.  I1, I2, Im : stator, rotor (referred) and
    magnetising current phasors, A RMS.  P_in : electrical input power, W.  P_stator : stator
    losses ``3|I1|^2 (R1 + R1sigma)``, W.  P_core : main-flux core loss ``3|Im|^2 R0``, W.
    P_ag : air-gap power, W.  P_rotor : rotor losses ``s*P_ag`` (copper and leakage core loss), W.
    P_mech : mechanical power delivered to the shaft ``(1 - s)*P_ag``, W (negative when the shaft
    drives the machine).  torque : electromagnetic torque ``P_ag/w_sync``, N m.
    """

    slip: np.ndarray
    Y: np.ndarray
    I1: np.ndarray
    I2: np.ndarray
    Im: np.ndarray
    P_in: np.ndarray
    P_stator: np.ndarray
    P_core: np.ndarray
    P_ag: np.ndarray
    P_rotor: np.ndarray
    P_mech: np.ndarray
    torque: np.ndarray


def operating_point(
    params: CircuitParameters, slip, voltage, frequency: float, pole_pairs: int
) -> OperatingPoint:
    """Currents, powers and torque of the circuit at phase voltage ``voltage`` (V RMS, the
    reference phasor) and the given slips."""
    p = params
    s = np.asarray(slip, float)
    V = np.asarray(voltage, float)
    Z0 = p.R0 + 1j * p.X0
    Y2 = rotor_admittance(s, p.R2, p.X2, p.R2sigma, p.X3)
    Zin = p.R1_total + 1j * p.X1 + Z0 / (1.0 + Z0 * Y2)
    Y = 1.0 / Zin
    I1 = V * Y
    E = I1 * Z0 / (1.0 + Z0 * Y2)  # air-gap voltage across the magnetising branch
    I2 = E * Y2
    Im = I1 - I2
    P_in = 3.0 * np.real(V * np.conj(I1))
    P_stator = 3.0 * np.abs(I1) ** 2 * p.R1_total
    P_core = 3.0 * np.abs(Im) ** 2 * p.R0
    P_ag = 3.0 * np.real(E * np.conj(I2))
    w_sync = 2.0 * np.pi * frequency / pole_pairs
    return OperatingPoint(
        slip=s,
        Y=Y,
        I1=I1,
        I2=I2,
        Im=Im,
        P_in=P_in,
        P_stator=P_stator,
        P_core=P_core,
        P_ag=P_ag,
        P_rotor=s * P_ag,
        P_mech=(1.0 - s) * P_ag,
        torque=P_ag / w_sync,
    )


# ----------------------------------------------------------------------------- bilinear form


def warped_slip(s, R2, R2sigma=0.0, X3=0.0):
    """The complex slip ``s'`` in which the 8-parameter circuit is the 6-parameter one:
    ``R2/s' = R2/s + R2sigma*sign(s) - j*X3*|s|``, i.e. ``s' = s/(1 + (R2sigma/R2)|s| - j(X3/R2) s|s|)``."""
    s = np.asarray(s, float)
    return s / (1.0 + (R2sigma / R2) * np.abs(s) - 1j * (X3 / R2) * s * np.abs(s))


def bilinear_coefficients(R1t, X1, R2, X2, R0, X0):
    """Coefficients of ``Zin(s) = (A + B*s)/(1 + C*s)`` for the 6-parameter circuit, and of the
    admittance ``Y = (a + b*s)/(1 + c*s)`` with ``a = 1/A, b = C/A, c = B/A``.

    Returns ``(A, B, C, a, b, c)`` (complex). ``A = Z1 + Z0``, ``C = (Z0 + jX2)/R2``,
    ``B = Z1*C + jX2*Z0/R2``."""
    Z1 = R1t + 1j * X1
    Z0 = R0 + 1j * X0
    A = Z1 + Z0
    C = (Z0 + 1j * X2) / R2
    B = Z1 * C + 1j * X2 * Z0 / R2
    return A, B, C, 1.0 / A, C / A, B / A


def bilinear_to_circuit(a, b, c, tie_x1_x2: bool = False) -> dict[str, float]:
    """Map admittance coefficients ``Y = (a + b*s)/(1 + c*s)`` back to the 6-parameter circuit.

    ``A = 1/a``, ``B = c/a``, ``C = b/a``, ``D = A*C - B = Z0^2/R2``. With ``X1``, ``X2`` free:
    ``Z0 = sqrt(R2*D)`` and ``R0 = R2*Re(C)`` give ``sqrt(R2) = Re(sqrt(D))/Re(C)`` (exact, but it
    leans on the small ``R0``, so it is ill-conditioned with noise). With the tie ``X1 = X2``:
    ``R2 = Im(A)/Im(C)`` (Lindsay and Barton (1972)). Returns a dict with ``R1t, X1, R2, X2, R0, X0``;
    values may be non-physical (negative, NaN) for data that do not come from such a circuit.
    """
    A = 1.0 / a
    B = c / a
    C = b / a
    D = A * C - B
    if tie_x1_x2:
        R2 = np.imag(A) / np.imag(C)
    else:
        rd = np.real(np.sqrt(D + 0j))
        R2 = (rd / np.real(C)) ** 2 if np.real(C) > 0 and rd > 0 else np.nan
    Z0 = np.sqrt(R2 * D + 0j)
    if np.real(Z0) < 0:  # the root with positive reactance and resistance
        Z0 = -Z0
    R0 = float(np.real(Z0)) if not tie_x1_x2 else float(R2 * np.real(C))
    X0 = float(np.imag(Z0))
    X1 = float(np.imag(A) - X0)
    X2 = float(R2 * np.imag(C) - X0) if not tie_x1_x2 else X1
    R1t = float(np.real(A) - R0)
    return {"R1t": R1t, "X1": X1, "R2": float(R2), "X2": X2, "R0": R0, "X0": X0}


# ----------------------------------------------------------------------------- temperature


def copper_factor(theta, theta_ref):
    """``R(theta)/R(theta_ref)`` for copper: ``(234.5 + theta)/(234.5 + theta_ref)``."""
    return (COPPER_INFERRED_ZERO_C + np.asarray(theta, float)) / (COPPER_INFERRED_ZERO_C + theta_ref)


def temperature_from_resistance(R, R_known, theta_known):
    """Copper temperature (deg C) at which the resistance is ``R``, given ``R_known`` at ``theta_known``."""
    return (COPPER_INFERRED_ZERO_C + theta_known) * np.asarray(R, float) / R_known - COPPER_INFERRED_ZERO_C


@dataclass(frozen=True)
class ThermalModel:
    """One-body thermal model ``C dtheta/dt = P - K(n)*(theta - theta_a)`` (paper eqs. 4-8).

    The conductance depends on speed: ``K(n) = K0 + (Kn - K0)*|n|/n_K``, interpolating the two
    cooling curves the paper measures (standstill and one speed). Its eq. 8 is garbled in the OCR;
    linear in the speed magnitude is this project's reading.

    Attributes
    ----------
    capacitance : J/K, thermal capacitance C.
    conductance_standstill : W/K, K0.
    conductance_at_speed : W/K, Kn at ``conductance_speed_rpm``.
    conductance_speed_rpm : rpm, the speed of the second cooling curve.
    ambient_temperature : deg C.
    """

    capacitance: float
    conductance_standstill: float
    conductance_at_speed: float
    conductance_speed_rpm: float
    ambient_temperature: float

    def conductance(self, speed_rpm):
        """K(n), W/K."""
        n = np.abs(np.asarray(speed_rpm, float))
        K0, Kn = self.conductance_standstill, self.conductance_at_speed
        return K0 + (Kn - K0) * n / self.conductance_speed_rpm

    def cooling_rate(self, speed_rpm):
        """``K(n)/C``, 1/s: the initial slope of a cooling curve divided by the temperature rise."""
        return self.conductance(speed_rpm) / self.capacitance

    def step(self, theta, power, speed_rpm, dt):
        """Advance the temperature by ``dt`` seconds with constant power (W) and speed (exact
        solution of the linear ODE over the step)."""
        return step_temperature(
            theta, power / self.capacitance, self.cooling_rate(speed_rpm), self.ambient_temperature, dt
        )


def step_temperature(theta, heating_rate, cooling_rate, theta_a, dt):
    """Exact step of ``dtheta/dt = h - r*(theta - theta_a)`` over ``dt`` with constant h (K/s)
    and r (1/s); ``r = 0`` is the adiabatic case."""
    r = np.asarray(cooling_rate, float)
    decay = np.exp(-r * dt)
    # (1 - exp(-r dt))/r, continuous at r = 0
    gain = np.where(r * dt > 1e-12, -np.expm1(-r * dt) / np.where(r > 0, r, 1.0), dt)
    return theta_a + (theta - theta_a) * decay + heating_rate * gain

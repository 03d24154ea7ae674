"""The standard's reference computation: the equivalent circuit from the DC resistance, the
no-load test and the locked-rotor (impedance) test, as IEEE 112's equivalent-circuit method
(method F) is publicly described, with the rotor resistance calibrated on one load point. It is
computed from the same tests the optimisers fit (``kind: loadtest``), as a reference beside them.

The standard texts (IEEE 112-2017, IEC 60034-28:2012) were not accessible to this project; the
steps follow the procedure as textbooks and application notes reproduce it, and each is stated:

1. ``R1`` from the DC resistance, referred to each test's winding temperature (234.5 C law).
2. No-load test at the reading nearest the load test's voltage: ``X_NL = Q0/(3 I0^2) = X1 + Xm``;
   friction and windage from the no-load series (:mod:`benchmark.problems.admittance.noload`).
3. Locked-rotor test at reduced frequency ``f_L`` (the reading of the largest current, about
   rated): ``R_LR = P_L/(3 I_L^2)``, ``X_LR = (f/f_L) Q_L/(3 I_L^2) = X1 + X2 Xm/(X2 + Xm)``.
4. The leakage split from the design: ``X1/(X1 + X2)`` = 0.5 (NEMA design A, D, wound rotor),
   0.4 (B), 0.3 (C), or a number; ``X1`` then solves the two equations of 2 and 3.
5. ``R2 = (R_LR - R1) ((X2 + Xm)/Xm)^2`` (core loss neglected at standstill), referred to the
   reference temperature.
6. Core loss at no load: ``P_fe = P0 - P_fw - 3 I0^2 R1`` at the air-gap voltage ``E0 = |V0 - I0 Z1|``:
   ``G_fe = P_fe/(3 E0^2)``, in series form ``R0 + jX0 = 1/(G_fe - j/Xm)``.
7. With load points: ``R2`` recalibrated so that the circuit draws the measured input power at the
   measured slip of the load point nearest the locked-rotor test's current (about rated load;
   the locked-rotor ``R2`` carries some skin effect even at reduced frequency).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from benchmark.core.errors import ConfigError
from benchmark.problems.admittance.circuit import copper_factor, input_admittance
from benchmark.problems.admittance.loadtest import LoadTest

__all__ = ["DESIGN_SHARE", "standard_circuit"]

#: X1/(X1 + X2) by design class, as IEEE 112's table of the leakage split is usually quoted.
DESIGN_SHARE = {"A": 0.5, "B": 0.4, "C": 0.3, "D": 0.5, "wound": 0.5}


def _share(design) -> float:
    if isinstance(design, str):
        if design not in DESIGN_SHARE:
            raise ConfigError(f"design: one of {sorted(DESIGN_SHARE)} or a number X1/(X1 + X2), got {design!r}")
        return DESIGN_SHARE[design]
    x = float(design)
    if not 0 < x < 1:
        raise ConfigError(f"design: a share X1/(X1 + X2) within (0, 1), got {x}")
    return x


def standard_circuit(lt: LoadTest, design="B") -> dict:
    """The circuit of steps 1-7 (ohm per phase at rated frequency, resistances at the reference
    temperature): ``R1, X1, R2, X2, R0, X0, X1+X2``, with ``Xm``, ``G_fe``, ``R2_locked``,
    ``friction_w`` and ``notes``. Needs the DC resistance, a no-load and a locked-rotor test."""
    missing = [w for w, ok in (("stator_dc_resistance", lt.R1_dc is not None), ("noload.csv", "noload" in lt.tables),
                               ("locked.csv", "locked" in lt.tables)) if not ok]
    if missing:
        raise ConfigError(f"the standard's computation needs {missing} in {lt.source}")
    f = lt.frequency
    theta_ref = lt.theta_ref if lt.theta_ref is not None else lt.theta_dc
    x = _share(design)
    notes = [f"leakage split X1/(X1 + X2) = {x:g} (design {design})"]
    nl, lr = lt.tables["noload"], lt.tables["locked"]
    load = lt.tables.get("load")
    V_rated = float(np.median(load.V)) if load is not None else float(nl.V.max())
    i = int(np.argmin(np.abs(nl.V - V_rated)))
    V0, I0, P0, Q0 = nl.V[i], nl.I[i], nl.P[i], nl.Q[i]
    R1_0 = float(lt.R1_at(None if nl.temperature is None else nl.temperature[i]))
    X_NL = Q0 / (3.0 * I0**2)
    j = int(np.argmax(lr.I))
    k = lr.frequency[j] / f
    R_LR = lr.P[j] / (3.0 * lr.I[j] ** 2)
    X_LR = lr.Q[j] / (3.0 * lr.I[j] ** 2) / k
    R1_L = float(lt.R1_at(None if lr.temperature is None else lr.temperature[j]))

    def gap(X1):
        X2, Xm = X1 * (1 - x) / x, X_NL - X1
        return X1 + X2 * Xm / (X2 + Xm) - X_LR

    X1 = brentq(gap, 1e-9 * X_LR, min(X_LR, 0.999 * X_NL), xtol=1e-14)
    X2, Xm = X1 * (1 - x) / x, X_NL - X1
    theta_L = theta_ref if lr.temperature is None else float(lr.temperature[j])
    R2_L = (R_LR - R1_L) * ((X2 + Xm) / Xm) ** 2 / float(copper_factor(theta_L, theta_ref))
    P_fw = lt.friction.power if lt.friction is not None else 0.0
    if lt.friction is None:
        notes.append("no friction and windage known: the core loss includes it")
    P_fe = P0 - P_fw - 3.0 * I0**2 * R1_0
    I0_phasor = I0 * (P0 - 1j * Q0) / (3.0 * V0 * I0)
    E0 = abs(V0 - I0_phasor * complex(R1_0, X1))
    G_fe = P_fe / (3.0 * E0**2)
    Z0 = 1.0 / complex(G_fe, -1.0 / Xm)
    R1 = float(lt.R1_at(theta_ref))
    out = {"R1": R1, "X1": X1, "R2": R2_L, "X2": X2, "R0": Z0.real, "X0": Z0.imag, "X1+X2": X1 + X2, "Xm": Xm,
           "G_fe": G_fe, "R2_locked": R2_L, "friction_w": P_fw,
           "notes": notes + [f"no-load reading at {V0:.4g} V per phase, locked-rotor reading at {lr.V[j]:.4g} V, "
                             f"{lr.I[j]:.4g} A per phase, {lr.frequency[j]:g} Hz"]}
    if load is not None and load.speed_rpm is not None:
        out.update(_load_point_r2(lt, out, load, lr.I[j], theta_ref))
    return out


def _load_point_r2(lt: LoadTest, c: dict, load, I_ref: float, theta_ref: float) -> dict:
    """Step 7: R2 such that the circuit draws the measured input power at the measured slip."""
    i = int(np.argmin(np.abs(load.I - I_ref)))
    s = 1.0 - load.speed_rpm[i] * lt.pole_pairs / (60.0 * load.frequency[i])
    if not s > 0:
        return {}
    theta = theta_ref if load.temperature is None else float(load.temperature[i])
    cu = float(copper_factor(theta, theta_ref))
    V = load.V[i]

    def power_gap(R2):
        Y = input_admittance(s, c["R1"] * cu, c["X1"], R2 * cu, c["X2"], c["R0"], c["X0"])
        return 3.0 * V**2 * float(np.real(Y)) - load.P[i]

    lo, hi = c["R2_locked"] / 4.0, 4.0 * c["R2_locked"]
    if power_gap(lo) * power_gap(hi) > 0:
        return {"notes": c["notes"] + ["R2 not recalibrated: no R2 within a factor 4 matches the load point"]}
    R2 = brentq(power_gap, lo, hi, xtol=1e-12)
    return {"R2": R2, "notes": c["notes"] + [f"R2 calibrated on the load point of {load.I[i]:.4g} A per phase, "
                                             f"slip {s:.5f} (locked-rotor R2 {c['R2_locked']:.4g} ohm)"]}

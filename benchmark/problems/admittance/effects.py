"""Steady-state (slip-sweep) effects: each one class, acting on a :class:`SweepCircuit`.

The diagnosis's base model is the 6-parameter circuit with ``X1 = X2`` (the effect catalogue):
``Z1 = R1t + jX``, ``Z0 = R0 + jX0``, ``Z2 = R2/s + jX``. An effect is what that circuit leaves out.
Both sides of an effect act on the same generalised circuit, :class:`SweepCircuit`, which
evaluates the input admittance of every reading (slip ``s``, phase voltage ``V``) with

* a per-reading copper factor on the stator and rotor resistances (warming),
* a rotor given by its admittance ``Y2(s)`` (single cage, two cages, deep bars, ``R2sigma``,
  ``X3``),
* a magnetising branch whose reactance, series resistance and parallel core-loss conductance
  may depend on the air-gap voltage ``|E|`` (saturation, voltage-dependent core loss),
* leakage reactances that may depend on the branch currents ``|I1|``, ``|I2|``,

solved by fixed-point iteration when anything depends on ``|E|`` or ``|I|``.

* **Plant** (:meth:`AdmittanceEffect.plant`): inject the effect at ``size`` (a documented,
  realistic range per class; the YAML's ``realistic`` overrides it) with a ``form`` that varies
  *how* the plant realises it (e.g. a double cage, a rectangular deep bar or L&B's quadratic
  law), so that a diagnosis keyed on one formula is caught out.
* **Augmentation** (:meth:`AdmittanceEffect.augment`): the base circuit plus the effect's own
  extra parameters (:attr:`extra_names`), in one canonical, signature-level form, fitted by the
  diagnosis from the base fit.

Sizes that depend on the test (saturation, leakage saturation) are given relative to the
sweep's own scales in :class:`SweepContext` (its highest air-gap voltage and its largest
current at standstill), so that one size means the same thing for every test design.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from benchmark.core.effects import Effect
from benchmark.problems.admittance.circuit import rotor_admittance
from benchmark.problems.admittance.rotor_forms import (
    _deep_bar,
    _quadratic_rotor,
    _rotor_resistance_rise,
    _two_cages,
)
from benchmark.problems.admittance.sweep_circuit import SweepCircuit, SweepContext, heat_profile

__all__ = [
    "SweepCircuit",
    "SweepContext",
    "AdmittanceEffect",
    "heat_profile",
    "DoubleCage",
    "MainSaturation",
    "IronLoss",
    "TemperatureDrift",
    "LeakageSaturation",
    "LeakageCoreLoss",
]


# ----------------------------------------------------------------------------- base class


class AdmittanceEffect(Effect):
    """An effect of the slip sweep. Subclasses set the class attributes and the methods.

    ``plant(circuit, size, ctx, form)`` returns the circuit with the effect injected;
    ``augment(circuit, extras, ctx)`` the base circuit plus the fitted extras (a 1-D array in
    :attr:`extra_names` order); ``extra_bounds``/``extra_starts`` bound and start the fit;
    ``session(size, form)`` may change the test itself (warming), default nothing.
    """

    problem = "admittance"

    def form_of(self, form: dict | None) -> dict:
        return {**self.form, **(form or {})}

    def session(self, size: float, form: dict | None = None) -> dict:
        """Changes to the bench session (the generator's ``motor.test``/``thermal`` keys)."""
        return {}

    def plant(self, circuit: SweepCircuit, size: float, ctx: SweepContext, form: dict | None = None) -> SweepCircuit:
        raise NotImplementedError

    def augment(self, circuit: SweepCircuit, extras: np.ndarray, ctx: SweepContext) -> SweepCircuit:
        raise NotImplementedError

    def extra_bounds(self, ctx: SweepContext) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError

    def extra_starts(self, ctx: SweepContext) -> list[np.ndarray]:
        lo, hi = self.extra_bounds(ctx)
        return [lo + 0.1 * (hi - lo)]


# ----------------------------------------------------------------------------- the effects


class DoubleCage(AdmittanceEffect):
    """Deep bars / a second cage: the rotor resistance rises (and its leakage falls) with rotor
    frequency ``|s| f``.

    Size ``r``: the rise of the rotor's effective resistance at standstill (rotor frequency =
    supply frequency) over its slip-frequency value, ``R2(s=1)/R2(s->0) - 1``. Realistic
    0.05-0.4: deep-bar cages of general-purpose (NEMA A/B) machines; double cages go higher.
    Forms: ``kind`` = ``double_cage`` (default; two parallel cages, cage B's corner slip
    ``corner`` = R_B/X_B, default 0.3), ``deep_bar`` (rectangular bar, Field's factors; ``bar_share`` of R2
    and half of X2 in the bar), ``quadratic`` (L&B's table: ``R2 (1 + r s^2)``, ``X2/(1 + r s^2/4)``).

    Augmentation: a two-cage rotor ``jX + (R_A/s) || (R_B/s + jX_B)`` with ``R_A || R_B = R2``,
    extras ``dc_rise`` = ``R_A/R2 - 1`` (the high-frequency resistance rise) and ``dc_corner``
    = ``log10(R_B/X_B)`` (the slip above which cage B blocks).
    """

    name = "double_cage"
    size_name = "rotor_resistance_rise_at_standstill"
    realistic = (0.05, 0.4)
    extra_names = ("dc_rise", "dc_corner")
    extra_units = ("p.u. of low-slip R2", "log10 of slip")
    physics = "second rotor cage / deep bars: rotor resistance and leakage depend on rotor frequency"
    shows_in = "conductance at large slip (braking, s > 1), both signs of s alike"

    def plant(self, circuit, size, ctx, form=None):
        form = self.form_of(form)
        kind = str(form.get("kind", "double_cage"))
        ratio = circuit.X2 / circuit.R2
        if kind == "quadratic":
            rotor = _quadratic_rotor(size)
        elif kind == "deep_bar":
            bar_r, bar_x = float(form.get("bar_share", 0.8)), 0.5

            def rise(h):
                return _rotor_resistance_rise(_deep_bar(h, bar_r, bar_x), 1.0, ratio) - size

            rotor = _deep_bar(brentq(rise, 1e-3, 20.0), bar_r, bar_x)
        elif kind == "double_cage":
            s_c = float(form.get("corner", 0.3))

            def rise(a):
                return _rotor_resistance_rise(_two_cages(a, s_c), 1.0, ratio) - size

            # the rise at s = 1 peaks at some a (cage B then carries too little): solve below it
            grid = np.logspace(-6, 4, 201)
            vals = np.array([rise(a) for a in grid])
            k = int(np.argmax(vals))
            if vals[k] < 0:
                raise ValueError(
                    f"effect_size.double_cage: {size} is beyond what two cages with corner {s_c} give "
                    f"({vals[k] + size:.3f}); lower the corner slip (effect_form.double_cage.corner)"
                )
            rotor = _two_cages(brentq(rise, 1e-7, grid[k]), s_c)
        else:
            raise ValueError(f"effect_form.double_cage.kind: double_cage, deep_bar or quadratic, got {kind!r}")
        return circuit.with_(rotor=_with_lb_terms(rotor, circuit))

    def extra_bounds(self, ctx):
        return np.array([0.0, -1.3]), np.array([6.0, 1.3])

    def extra_starts(self, ctx):
        return [np.array([0.3, 0.0]), np.array([1.0, 0.5]), np.array([0.1, -0.5])]

    def augment(self, circuit, extras, ctx):
        a, lg = float(extras[0]), float(extras[1])
        if a <= 1e-9:
            return circuit
        return circuit.with_(rotor=_two_cages(a, 10.0**lg))


def _with_lb_terms(rotor, circuit):
    """Keep an 8-parameter plant's R2sigma, X3 when a rotor form replaces the single cage."""
    if circuit.R2sigma == 0.0 and circuit.X3 == 0.0:
        return rotor
    return _series_rotor(rotor, lambda s: circuit.R2sigma * np.sign(s) - 1j * circuit.X3 * np.abs(s))


def _series_rotor(inner, z_of_s):
    """The rotor admittance ``inner(s, R2, X2)`` with a slip-dependent series impedance
    ``z_of_s(s)`` (ohm) added: ``Y / (1 + z Y)``."""

    def rotor(s, R2, X2):
        s = np.asarray(s, float)
        Y = inner(s, R2, X2)
        return Y / (1.0 + z_of_s(s) * Y)

    return rotor


def _current_leakage(c: float, I_ref: float, n):
    """Leakage factors ``(k1, k2)`` on X1, X2 that fall with the currents:
    ``1 / (1 + c (|I| / I_ref)^n)``."""

    def leak(I1, I2):
        return 1.0 / (1.0 + c * (I1 / I_ref) ** n), 1.0 / (1.0 + c * (I2 / I_ref) ** n)

    return leak


class MainSaturation(AdmittanceEffect):
    """Main-flux saturation: the magnetising reactance falls with the air-gap voltage ``|E|``.

    Size ``k``: the fractional fall of X0 at the sweep's highest air-gap voltage ``E_top``
    (``X0(E_top) = (1 - k) X0``, X0 the low-flux value). Realistic 0.01-0.08 for sweeps that
    reach 0.4-0.6 of rated voltage (L&B test at 0.16-0.4: their machine is close to linear
    there). Forms: ``exponent`` n of ``X0/(1 + c (|E|/E_top)^n)`` (default 4); ``exponent: 1``
    is Frohlich's law ``X0 (1 - k|E|/E_top)``; ``loss: parallel`` keeps the core-loss
    conductance constant instead of the series R0.

    Augmentation: ``X0/(1 + c (|E|/E_top)^n)``, ``c = f/(1 - f)``, with extras ``ms_fall`` = f
    (the fall of X0 at the top air-gap voltage; < 0: a reactance rising with flux, as at very
    low flux) and ``ms_exp`` = n.
    """

    name = "main_saturation"
    size_name = "X0_fall_at_top_voltage"
    realistic = (0.01, 0.08)
    extra_names = ("ms_fall", "ms_exp")
    extra_units = ("p.u. of low-flux X0", "-")
    physics = "magnetising reactance falls with the air-gap flux"
    shows_in = "susceptance near synchronism (s ~ 0), different at each voltage level"

    def plant(self, circuit, size, ctx, form=None):
        form = self.form_of(form)
        n = float(form.get("exponent", 4.0))
        E_top = ctx.E_top
        if n == 1.0:

            def x0_of_e(E):
                return 1.0 - size * np.asarray(E) / E_top
        else:
            c = size / (1.0 - size)

            def x0_of_e(E):
                return 1.0 / (1.0 + c * (np.asarray(E) / E_top) ** n)

        if str(form.get("loss", "series")) == "parallel":
            # the branch R0 + jX0 as a constant core-loss conductance across a pure reactance
            Zm = complex(circuit.R0, circuit.X0)
            G = float(np.real(1.0 / Zm))
            Xp = float(-1.0 / np.imag(1.0 / Zm))
            return circuit.with_(R0=0.0, X0=Xp, x0_of_e=x0_of_e, gfe_of_e=lambda E: G)
        return circuit.with_(x0_of_e=x0_of_e)

    def extra_bounds(self, ctx):
        return np.array([-0.2, 0.5]), np.array([0.5, 8.0])

    def extra_starts(self, ctx):
        return [np.array([0.02, 2.0]), np.array([0.02, 5.0])]

    def augment(self, circuit, extras, ctx):
        c = float(extras[0]) / (1.0 - float(extras[0]))
        n = float(extras[1])
        E_top = ctx.E_top
        return circuit.with_(x0_of_e=lambda E: 1.0 / (1.0 + c * (np.asarray(E) / E_top) ** n))


class IronLoss(AdmittanceEffect):
    """Core loss that is not a constant resistance: the main-flux core loss grows as ``|E|^(2+q)``
    (hysteresis: Steinmetz ``B^beta``, ``beta`` 2.2-3 in the Rayleigh region of a reduced-voltage
    test, about 1.6-2 near rated flux), so the core-loss conductance across the magnetising branch
    varies with the air-gap voltage. (A constant core-loss conductance is the base's R0, exactly:
    at one frequency a shunt conductance across X0 is a series R0.)

    Size ``q``: ``d ln G_fe / d ln |E|`` at the sweep's top air-gap voltage. Realistic 0.2-1.0.
    Forms: ``kind`` = ``power`` (default, ``G_fe ~ |E|^q``) or ``two_term`` (an eddy-current
    part constant plus a Rayleigh hysteresis part ``~ |E|``, its share = q at E_top).

    Augmentation: the series core-loss resistance ``R0 (|E|/E_top)^q``, extra ``fe_q``.
    """

    name = "iron_loss"
    size_name = "core_loss_conductance_exponent"
    realistic = (0.2, 1.0)
    extra_names = ("fe_q",)
    extra_units = ("-",)
    physics = "core-loss conductance across the magnetising branch, varying with the flux"
    shows_in = "conductance near synchronism (s ~ 0), different at each voltage level"

    def plant(self, circuit, size, ctx, form=None):
        form = self.form_of(form)
        kind = str(form.get("kind", "power"))
        Zm = complex(circuit.R0, circuit.X0)
        G = float(np.real(1.0 / Zm))
        Xp = float(-1.0 / np.imag(1.0 / Zm))
        E_top = ctx.E_top
        if kind == "power":

            def gfe(E):
                return G * (np.asarray(E) / E_top) ** size
        elif kind == "two_term":
            h = min(float(size), 1.0)

            def gfe(E):
                return G * (1.0 - h + h * np.asarray(E) / E_top)
        else:
            raise ValueError(f"effect_form.iron_loss.kind: power or two_term, got {kind!r}")
        return circuit.with_(R0=0.0, X0=Xp, gfe_of_e=gfe)

    def extra_bounds(self, ctx):
        return np.array([-1.5]), np.array([3.0])

    def extra_starts(self, ctx):
        return [np.array([0.3])]

    def augment(self, circuit, extras, ctx):
        q = float(extras[0])
        E_top = ctx.E_top
        return circuit.with_(r0_of_e=lambda E: (np.maximum(np.asarray(E), 1e-6 * E_top) / E_top) ** q)


class TemperatureDrift(AdmittanceEffect):
    """The windings warm during the session (one-body thermal model, copper law, the model
    section 5), so R1 and R2 drift with acquisition time.

    Size: the winding temperature rise from the first to the last reading, K. Realistic 3-15 K
    (L&B: about 5 K over one sweep at 30 V; a session of several sweeps and levels warms more).
    The generator's thermal model does the warming (``session``); its heating scale is set so
    the rise is ``size``. Forms: ``cooling: false`` (adiabatic) instead of the preset's cooling.

    Augmentation: ``R1t``, ``R2`` times ``1 + td_rise * h(t)`` with ``h`` the normalised heat
    profile of the windings computed from the measured currents and times
    (:func:`heat_profile`); extra ``td_rise`` (the fractional resistance rise over the session).
    """

    name = "temperature_drift"
    size_name = "temperature_rise"
    size_unit = "K"
    realistic = (3.0, 15.0)
    extra_names = ("td_rise",)
    extra_units = ("p.u. of first reading's resistance",)
    physics = "winding resistances rise during the test (copper law, one-body thermal model)"
    shows_in = "residual that follows acquisition order; up- vs down-sweep hysteresis"

    def session(self, size, form=None):
        form = self.form_of(form)
        return {"warming": True, "target_rise_K": float(size), "cooling": bool(form.get("cooling", True))}

    def plant(self, circuit, size, ctx, form=None):
        return circuit  # the warming is the generator's thermal model (see session)

    def extra_bounds(self, ctx):
        return np.array([-0.05]), np.array([0.15])

    def extra_starts(self, ctx):
        return [np.array([0.01])]

    def augment(self, circuit, extras, ctx):
        return circuit.with_(copper=1.0 + float(extras[0]) * ctx.heat)


class LeakageSaturation(AdmittanceEffect):
    """Saturation of the leakage paths: the leakage reactance falls at high current.

    Size: the fractional fall of the rotor leakage reactance at standstill at the top voltage
    level. Realistic 0.01-0.06 (L&B's model F: ``X3/X2`` = 0.017 at 30 V). Forms: ``kind`` =
    ``slip`` (default, L&B's ``X2 - X3|s|`` with ``X3 = size*X2``) or ``current`` (X1 and X2
    fall with their own branch current, ``1/(1 + c (|I|/I_stall)^exponent)``, exponent 2).

    Augmentation: both drivers, L&B's ``-X3|s|`` in the rotor and a fall of X1, X2 with their
    branch currents ``1/(1 + c (|I|/I_stall)^2)``: extras ``X3_pu`` = X3/X2 and ``ls_fall`` =
    ``c/(1 + c)`` (the fall at the standstill current of the top level). The current-driven
    part is what makes the effect differ between voltage levels.
    """

    name = "leakage_saturation"
    size_name = "leakage_fall_at_standstill"
    realistic = (0.01, 0.06)
    extra_names = ("X3_pu", "ls_fall")
    extra_units = ("p.u. of X2", "p.u. of X1, X2 (fall at I_stall)")
    physics = "leakage reactance falls at high current (L&B: X2 - X3|s|)"
    shows_in = "susceptance at large slip (B too small at s = 2, too large near synchronism)"

    def plant(self, circuit, size, ctx, form=None):
        form = self.form_of(form)
        kind = str(form.get("kind", "slip"))
        if kind == "slip":
            X3 = size * circuit.X2
            if circuit.rotor is None:
                return circuit.with_(X3=circuit.X3 + X3)
            return circuit.with_(rotor=_series_rotor(circuit.rotor, lambda s: -1j * X3 * np.abs(s)))
        if kind == "current":
            n = float(form.get("exponent", 2.0))
            return circuit.with_(leak_of_i=_current_leakage(size / (1.0 - size), ctx.I_stall, n))
        raise ValueError(f"effect_form.leakage_saturation.kind: slip or current, got {kind!r}")

    def extra_bounds(self, ctx):
        return np.array([-0.05, -0.1]), np.array([0.15, 0.3])

    def extra_starts(self, ctx):
        return [np.array([0.01, 0.0]), np.array([0.0, 0.02])]

    def augment(self, circuit, extras, ctx):
        out = circuit.with_(X3=float(extras[0]) * circuit.X2)
        f = float(extras[1])
        if f == 0.0:
            return out
        return out.with_(leak_of_i=_current_leakage(f / (1.0 - f), ctx.I_stall, 2))


class LeakageCoreLoss(AdmittanceEffect):
    """Lindsay-Barton's leakage-flux core loss: ``R1sigma`` in series with the stator and
    ``R2sigma*sign(s)`` in the rotor (constant magnitude, the sign of the slip).

    Size: ``R2sigma/R2``. Realistic 0.04-0.2 (L&B's model F: 0.116). Forms: ``r1_ratio`` =
    ``R1sigma/R2sigma`` (default 0.18, model F's); ``smooth``: a slip over which the sign turns
    (``tanh(s/smooth)``, default 0: a hard sign).

    Augmentation: ``R2sigma`` (extra ``R2sigma_pu`` = R2sigma/R2). ``R1sigma`` acts only with
    ``R1`` at one frequency (Lindsay and Barton (1972)), so it is left in the base's ``R1t``.
    """

    name = "leakage_core_loss"
    size_name = "R2sigma_over_R2"
    realistic = (0.04, 0.2)
    extra_names = ("R2sigma_pu",)
    extra_units = ("p.u. of R2",)
    physics = "leakage-flux core loss: R1sigma (stator), R2sigma*sign(s) (rotor)"
    shows_in = "susceptance changes sign across s = 0; conductance low at s = 2"

    def plant(self, circuit, size, ctx, form=None):
        form = self.form_of(form)
        R2s = size * circuit.R2
        R1s = float(form.get("r1_ratio", 0.18)) * R2s
        smooth = float(form.get("smooth", 0.0))
        out = circuit.with_(R1t=circuit.R1t + R1s, R1sigma=circuit.R1sigma + R1s)
        if smooth <= 0 and circuit.rotor is None:
            return out.with_(R2sigma=circuit.R2sigma + R2s)
        inner = circuit.rotor or (lambda s, R2, X2: rotor_admittance(s, R2, X2, circuit.R2sigma, circuit.X3))
        sign = (lambda s: np.tanh(s / smooth)) if smooth > 0 else np.sign
        return out.with_(rotor=_series_rotor(inner, lambda s: R2s * sign(s)))

    def extra_bounds(self, ctx):
        return np.array([-0.2]), np.array([0.6])

    def extra_starts(self, ctx):
        return [np.array([0.05])]

    def augment(self, circuit, extras, ctx):
        return circuit.with_(R2sigma=float(extras[0]) * circuit.R2)

"""The steady-state identification problem of Lindsay and Barton (Lindsay and Barton).

Cost
----
``S^2 = (1/n) * sum(Delta^2)`` over the ``n = 2N`` conductance and susceptance points of the N
readings, ``Delta = (Y_calc - Y_meas)/Y_unit`` per component, with ``Y_unit`` the full-scale
admittance (``normalisation: full_scale``; the data's ``full_scale_admittance``, else the largest
measured ``|Y|``) or the measured ``|Y|`` of the reading (``normalisation: measured``). With
``stalled_torque_weight = w > 0`` the term ``w*((T_calc - T_meas)/T_meas)^2`` at standstill
(``s = 1``) is added inside the sum. :meth:`AdmittanceProblem.rms_error_percent` gives
``100*sqrt(S^2)``, the paper's "mean error".

Searched parameters (ohm at the test frequency, referred to the reference temperature)
--------------------------------------------------------------------------------------
8-parameter model (default): ``R1_total, X1, R2, X2, R0, X0, R2sigma, X3``; 6-parameter model:
``R1_total, X1, R2, X2, R0, X0``; ``tie_x1_x2: true`` drops ``X2`` (``X2 = X1``).
``R1_total = R1 + R1sigma``: at one frequency and temperature the admittance sees only the sum.
When the data give the stator DC resistance, :meth:`AdmittanceProblem.estimate` also reports
``R1`` (the DC value referred to the reference temperature) and ``R1sigma = R1_total - R1``;
otherwise it reports ``R1_total`` only (Lindsay and Barton (1972), identifiability).

Temperature compensation
------------------------
The windings warm during the sweep. From the DC stator resistance before and after
(``stator_dc_resistance``), the temperature rise is known at two instants; between them the
one-body thermal model ``dtheta/dt = h*P(t) - r(n)*(theta - theta_a)`` is integrated along the
readings, with the heat ``P`` either the measured losses ``3 V^2 G - T*w_mech`` (when a torque
column is present: all electrical losses, shaft power removed) or ``|I1|^2`` (the paper's
assumption), the cooling rates ``r(n) = K(n)/C`` from the data's ``thermal`` block (zero, i.e.
adiabatic, without one) and the unknown heating scale ``h`` solved so that the end temperature
matches the second DC reading (the paper iterates the thermal capacitance for the same purpose).
Each reading is then computed with ``R1(theta_i)``, ``R2(theta_i)`` (copper, 234.5 C law); the
core-loss terms ``R1sigma, R2sigma, R0`` do not follow temperature.

Hook for the Lindsay-Barton plugin
----------------------------------
:meth:`AdmittanceProblem.initial_guess` (``"A"`` or ``"E"``) returns the paper's initial models from
the data alone, without evaluating the cost (see :mod:`plugins.lindsay_barton`).
"""

from __future__ import annotations

import numpy as np

from benchmark.core.errors import ConfigError
from benchmark.core.problem import Problem
from benchmark.problems.admittance.circuit import (
    input_admittance,
)
from benchmark.problems.admittance.data import AdmittanceData
from benchmark.problems.admittance.regression import bilinear_regression
from benchmark.problems.admittance.thermal import TemperatureProfile, estimate_temperatures

__all__ = [
    "AdmittanceProblem",
    "TemperatureProfile",
    "estimate_temperatures",
    "bilinear_regression",
    "parameter_names_for",
]

NAMES_8 = ("R1_total", "X1", "R2", "X2", "R0", "X0", "R2sigma", "X3")
NAMES_6 = NAMES_8[:6]
HEAT_MODELS = ("auto", "losses", "current_squared")
NORMALISATIONS = ("full_scale", "measured")


def parameter_names_for(model: int, tie_x1_x2: bool) -> tuple[str, ...]:
    names = NAMES_8 if model == 8 else NAMES_6
    return tuple(n for n in names if not (tie_x1_x2 and n == "X2"))


# ----------------------------------------------------------------------------- the problem


class AdmittanceProblem(Problem):
    """Slip-sweep admittance fit (see the module docstring).

    Parameters
    ----------
    data : the sweep(s).
    lower, upper : bounds in :attr:`parameter_names` order.
    model : 8 (default) or 6.
    normalisation : ``full_scale`` or ``measured``.
    stalled_torque_weight : weight of the stalled-torque term (0: off; needs a torque column).
    temperature_compensation : ``auto`` (on when the data allow it), True or False.
    heat_model : ``auto``, ``losses`` or ``current_squared`` (see the module docstring).
    tie_x1_x2 : search ``X1`` only, with ``X2 = X1``.
    truth : true parameters (the scoring keys of :meth:`estimate`), or None.
    reference_temperature : deg C to refer resistances to (None: the data's, else the start).
    """

    name = "admittance"
    #: Per-phase circuit elements, ohm (reactances at the test frequency); R1 and R1sigma split R1_total.
    units = {n: "ohm" for n in (*NAMES_8, "R1", "R1sigma")}
    #: the data set's truth document (truth.yaml or the in-memory one), for scoring scripts only
    truth_document: dict | None = None

    def __init__(
        self,
        data: AdmittanceData,
        lower,
        upper,
        model: int = 8,
        normalisation: str = "full_scale",
        stalled_torque_weight: float = 0.0,
        temperature_compensation="auto",
        heat_model: str = "auto",
        tie_x1_x2: bool = False,
        truth: dict | None = None,
        reference_temperature: float | None = None,
    ):
        if model not in (6, 8):
            raise ConfigError(f"problem.model: 8 (Lindsay-Barton 8-parameter, default) or 6, got {model!r}")
        if normalisation not in NORMALISATIONS:
            raise ConfigError(f"problem.normalisation: one of {list(NORMALISATIONS)}, got {normalisation!r}")
        if heat_model not in HEAT_MODELS:
            raise ConfigError(f"problem.heat_model: one of {list(HEAT_MODELS)}, got {heat_model!r}")
        if not (np.isfinite(stalled_torque_weight) and stalled_torque_weight >= 0):
            raise ConfigError(f"problem.stalled_torque_weight: must be >= 0, got {stalled_torque_weight!r}")
        self.data = data
        self.model = int(model)
        self.normalisation = normalisation
        self.tie_x1_x2 = bool(tie_x1_x2)
        self.parameter_names = parameter_names_for(self.model, self.tie_x1_x2)
        self.lower = np.asarray(lower, float)
        self.upper = np.asarray(upper, float)
        self.check_bounds()

        s = np.asarray(data.slip, float)
        self._s = s
        Ym = data.Y
        self._Ym = Ym
        self.full_scale_admittance = float(data.full_scale_admittance or np.max(np.abs(Ym)))
        unit = self.full_scale_admittance if normalisation == "full_scale" else np.abs(Ym)
        if np.any(unit <= 0):
            raise ConfigError("problem.normalisation: 'measured' needs non-zero measured admittances")
        self._w = np.broadcast_to(1.0 / unit, s.shape).astype(float)
        self._n_res = 2 * len(s)

        # temperature compensation
        comp = temperature_compensation
        can = data.stator_dc_resistance is not None and data.time is not None
        self.profile: TemperatureProfile | None = None
        self._comp_note = ""
        if comp == "auto":
            comp = can
            if not can:
                self._comp_note = (
                    "off: the data give no stator_dc_resistance [before, after] or no time column"
                )
        elif comp is True and not can:
            raise ConfigError(
                "problem.temperature_compensation: true needs 'stator_dc_resistance' [before, after] "
                f"in meta.yaml and a 'time' column in the sweep tables of {data.source}"
            )
        elif comp not in (True, False):
            raise ConfigError(f"problem.temperature_compensation: auto, true or false, got {comp!r}")
        if comp:
            self.profile = estimate_temperatures(data, heat_model, reference_temperature)
            self._k = self.profile.factor
            self._dR1 = self.profile.R1_ref * (self._k - 1.0)
        else:
            self._k = np.ones_like(s)
            self._dR1 = np.zeros_like(s)
        self.compensated = bool(comp)
        # R1 referred to the reference temperature: separable from R1sigma only via the DC value
        self.R1_dc: float | None = None
        if self.profile is not None:
            self.R1_dc = self.profile.R1_ref
        elif data.stator_dc_resistance is not None:
            self.R1_dc = float(np.mean(data.stator_dc_resistance))

        # stalled torque
        self.stalled_torque_weight = float(stalled_torque_weight)
        self._stall = None
        if self.stalled_torque_weight > 0:
            if data.torque is None:
                raise ConfigError(
                    "problem.stalled_torque_weight: > 0 needs a 'torque' column in the sweep tables "
                    f"of {data.source}"
                )
            self._stall = self._stalled_reading()
        self.truth = truth
        self.w_sync = 2 * np.pi * data.frequency / data.pole_pairs

    # -- helpers --------------------------------------------------------------------------

    def _stalled_reading(self):
        """(torque at s = 1, voltage, copper factor, stator dR1) from the readings at or around s = 1."""
        s, T = self._s, self.data.torque
        at = np.abs(s - 1.0) < 1e-9
        if at.any():
            idx = np.where(at)[0]
            return (
                float(T[idx].mean()),
                float(self.data.voltage[idx].mean()),
                float(self._k[idx].mean()),
                float(self._dR1[idx].mean()),
            )
        below, above = np.where(s < 1)[0], np.where(s > 1)[0]
        if not len(below) or not len(above):
            raise ConfigError("problem.stalled_torque_weight: the sweep does not pass standstill (s = 1)")
        i = below[np.argmax(s[below])]
        j = above[np.argmin(s[above])]
        f = (1.0 - s[i]) / (s[j] - s[i])

        def lerp(v):
            return float(v[i] + f * (v[j] - v[i]))

        return lerp(T), lerp(self.data.voltage), lerp(self._k), lerp(self._dR1)

    def full_parameters(self, X: np.ndarray) -> dict[str, np.ndarray]:
        """Columns ``(n_pop, 1)`` of every circuit parameter for the population ``X``."""
        X = np.atleast_2d(np.asarray(X, float))
        cols = {n: X[:, i : i + 1] for i, n in enumerate(self.parameter_names)}
        if self.tie_x1_x2:
            cols["X2"] = cols["X1"]
        zero = np.zeros((len(X), 1))
        cols.setdefault("R2sigma", zero)
        cols.setdefault("X3", zero)
        return cols

    def _valid(self, c) -> np.ndarray:
        ok = np.ones(len(c["R2"]), bool)
        for v in c.values():
            ok &= np.isfinite(v[:, 0])
        for n in ("R1_total", "R0", "R2sigma", "X1", "X2"):
            ok &= c[n][:, 0] >= 0
        for n in ("R2", "X0"):
            ok &= c[n][:, 0] > 0
        return ok

    def admittance(self, X: np.ndarray) -> np.ndarray:
        """Model admittance at every reading, ``(n_pop, N)`` complex S (temperature-compensated)."""
        c = self.full_parameters(X)
        with np.errstate(all="ignore"):
            return input_admittance(
                self._s,
                c["R1_total"] + self._dR1,
                c["X1"],
                c["R2"] * self._k,
                c["X2"],
                c["R0"],
                c["X0"],
                c["R2sigma"],
                c["X3"],
            )

    def stalled_torque(self, X: np.ndarray) -> np.ndarray:
        """Model torque at standstill at the stalled reading's voltage and temperature, N m."""
        c = self.full_parameters(X)
        T_meas, V, k, dR1 = self._stall if self._stall is not None else (None, self.data.voltage[0], 1.0, 0.0)
        Z0 = c["R0"] + 1j * c["X0"]
        Z2 = c["R2"] * k + c["R2sigma"] + 1j * (c["X2"] - c["X3"])
        with np.errstate(all="ignore"):
            Zin = c["R1_total"] + dR1 + 1j * c["X1"] + Z0 * Z2 / (Z0 + Z2)
            I2 = (V / Zin) * Z0 / (Z0 + Z2)
        return (3 * np.abs(I2) ** 2 * np.real(Z2) / self.w_sync)[:, 0]

    # -- Problem interface ------------------------------------------------------------------

    def residuals_batch(self, X: np.ndarray) -> np.ndarray:
        X = np.atleast_2d(np.asarray(X, float))
        c = self.full_parameters(X)
        Y = self.admittance(X)
        E = (Y - self._Ym) * self._w
        R = np.concatenate([E.real, E.imag], axis=1) / np.sqrt(self._n_res)
        if self._stall is not None:
            T = self.stalled_torque(X)
            rt = np.sqrt(self.stalled_torque_weight / self._n_res) * (T - self._stall[0]) / self._stall[0]
            R = np.concatenate([R, rt[:, None]], axis=1)
        bad = ~self._valid(c) | ~np.all(np.isfinite(R), axis=1)
        R[bad] = np.inf
        return R

    def residuals(self, x: np.ndarray) -> np.ndarray:
        return self.residuals_batch(np.asarray(x, float)[None, :])[0]

    def evaluate(self, X: np.ndarray) -> np.ndarray:
        R = self.residuals_batch(X)
        with np.errstate(invalid="ignore"):
            cost = np.einsum("ij,ij->i", R, R)
        return np.where(np.isfinite(cost), cost, np.inf)

    def rms_error_percent(self, x: np.ndarray) -> float:
        """The paper's mean error: ``100*sqrt(S^2)`` over G and B only (no torque term)."""
        r = self.residuals(x)[: self._n_res]
        return float(100 * np.sqrt(r @ r))

    def estimate(self, x: np.ndarray) -> dict[str, float]:
        c = self.full_parameters(np.asarray(x, float)[None, :])
        names = list(NAMES_8 if self.model == 8 else NAMES_6)
        out = {n: float(c[n][0, 0]) for n in names}
        if self.R1_dc is not None:
            out["R1"] = float(self.R1_dc)
            out["R1sigma"] = out["R1_total"] - self.R1_dc
        return out

    def truth_for_scoring(self, true_params: dict | None) -> dict[str, float] | None:
        """The true values under the names :meth:`estimate` reports (``R1_total = R1 + R1sigma``)."""
        if true_params is None:
            return None
        t = {k: float(v) for k, v in true_params.items()}
        t.setdefault("R1sigma", 0.0)
        t.setdefault("R2sigma", 0.0)
        t.setdefault("X3", 0.0)
        if "R1" in t:
            t["R1_total"] = t["R1"] + t["R1sigma"]
        keys = self.estimate(0.5 * (self.lower + self.upper)).keys()
        return {k: t[k] for k in keys if k in t}

    #: What the cost is measured in (figure labels).
    cost_unit = "S$^2$: mean squared G, B misfit, full scale = 1"

    def plots(self, x, record: dict) -> list:
        """This problem's figures of a run (not yet drawn): see :mod:`benchmark.problems.admittance.figures`."""
        from benchmark.problems.admittance.figures import admittance_plots

        return admittance_plots(self, x, record)

    def describe(self) -> dict:
        d = self.data
        info = {
            "data": d.source,
            "files": d.files,
            "readings": int(d.n),
            "frequency_hz": d.frequency,
            "pole_pairs": d.pole_pairs,
            "voltage_v": sorted({float(v) for v in np.round(d.voltage, 6)}),
            "slip_range": [float(self._s.min()), float(self._s.max())],
            "model": f"{self.model}-parameter" + (" (X1 = X2 tied)" if self.tie_x1_x2 else ""),
            "cost": "S^2 = mean over G and B of ((Y_calc - Y_meas)/Y_unit)^2"
            + (f" + stalled-torque term (weight {self.stalled_torque_weight})" if self._stall else ""),
            "normalisation": self.normalisation,
            "full_scale_admittance_s": self.full_scale_admittance,
            "temperature_compensation": self._describe_compensation(),
            "identifiability": self.identifiability_notes(),
        }
        return info

    def quality_warnings(self, x) -> list[str]:
        """A negative R1sigma (a stray-loss resistance cannot be negative) is reported with why:
        R1sigma = R1_total - R1 (DC), so it is negative when the fitted R1_total comes out below
        the DC resistance, within the error of R1_total at realistic noise; the circuit is
        still valid (only the sum R1_total acts)."""
        est = self.estimate(x)
        if est.get("R1sigma", 0.0) < 0:
            return [f"R1sigma = {est['R1sigma']:.3g} ohm is negative (not physical): R1sigma = R1_total - R1 with "
                    "R1 the "
                    f"DC resistance {est['R1']:.4g} ohm, and the fitted R1_total = {est['R1_total']:.4g} ohm came out "
                    "below it; only R1_total acts on the admittance, so read R1sigma as 0 within the uncertainty of "
                    "R1_total (see standard_error)"]
        return []

    def _describe_compensation(self) -> dict:
        if self.profile is None:
            return {
                "active": False,
                "note": self._comp_note or "off (problem.temperature_compensation: false)",
            }
        p = self.profile
        return {
            "active": True,
            "heat_model": p.heat_model,
            "cooling_rates_known": p.cooling,
            "theta_before_c": p.theta_before,
            "theta_after_c": p.theta_after,
            "theta_ref_c": p.theta_ref,
            "theta_first_reading_c": float(p.theta[0]),
            "theta_last_reading_c": float(p.theta[-1]),
            "R1_dc_at_ref_ohm": p.R1_ref,
            "notes": p.notes,
        }

    def identifiability_notes(self) -> list[str]:
        notes = []
        if self.R1_dc is None:
            notes.append(
                "R1 and R1sigma act only as their sum at one frequency: R1_total = R1 + R1sigma is "
                "reported; give stator_dc_resistance to separate them"
            )
        else:
            notes.append(
                "R1 is the DC stator resistance referred to the reference temperature (measured, not "
                "fitted); R1sigma = R1_total - R1 inherits the error of R1_total"
            )
        if not self.tie_x1_x2:
            if self._s.min() >= 0 and self.model == 8:
                notes.append(
                    "no generating-region readings (s < 0): re-referring the rotor trades R2sigma "
                    "against the X1/X2 split without changing Y; tie X1 = X2 (problem.tie_x1_x2)"
                )
            else:
                notes.append(
                    "X1 and X2 are separated only through the small R0 and (8-parameter) the sign "
                    "change of R2sigma at s = 0: their split is weakly determined at realistic noise"
                )
        notes.append("R0 is weakly determined at low voltage: quote its spread over noise realisations")
        return notes

    # -- the hook used by plugins.lindsay_barton ---------------------------------------------

    def initial_guess(self, kind: str) -> np.ndarray | None:
        """The paper's initial models from the data alone (no cost evaluation), clipped into the bounds:

        * ``"A"``: crude reading of the admittance at synchronous speed (``Z1 + Z0``) and at
          standstill (``Z1 + Z2``, magnetising branch neglected), split equally between stator and
          rotor; second-order terms set arbitrarily (``R2sigma = 0.05 R2``, ``X3 = 0.02 X2``).
        * ``"E"``: the Sanathanan-Koerner regression of the bilinear form (8-parameter: in the warped
          slip, with an outer search over ``R2sigma/R2``, ``X3/R2``), mapped back to the circuit with
          ``X1``, ``X2`` free when that gives a circuit inside the bounds, else with the tie ``X1 = X2``
          (:attr:`last_mapping` says which); with temperature compensation the data are then referred
          to the reference temperature with that circuit and the regression repeated until the circuit
          stops changing (at most 10 passes).

        Returns None for an unknown kind."""
        kind = str(kind).upper()
        if kind == "A":
            vals = self._model_a()
        elif kind == "E":
            vals = self._model_e()
        else:
            return None
        x = np.array([vals[n] for n in self.parameter_names], float)
        span = self.upper - self.lower
        return np.clip(
            np.where(np.isfinite(x), x, 0.5 * (self.lower + self.upper)),
            self.lower + 1e-6 * span,
            self.upper - 1e-6 * span,
        )

    def _admittance_at(self, s0: float) -> complex:
        order = np.argsort(self._s, kind="stable")
        s_sorted, Y_sorted = self._s[order], self._Ym[order]
        near = np.abs(s_sorted - s0) < 1e-9
        if near.any():
            return complex(Y_sorted[near].mean())
        return complex(np.interp(s0, s_sorted, Y_sorted.real) + 1j * np.interp(s0, s_sorted, Y_sorted.imag))

    def _model_a(self) -> dict[str, float]:
        Z_nl = 1.0 / self._admittance_at(0.0)
        Z_sc = 1.0 / self._admittance_at(1.0)
        R = Z_sc.real / 2
        X = Z_sc.imag / 2
        return {
            "R1_total": R,
            "X1": X,
            "R2": R,
            "X2": X,
            "R0": Z_nl.real - R,
            "X0": Z_nl.imag - X,
            "R2sigma": 0.05 * R,
            "X3": 0.02 * X,
        }

    def _model_e(self) -> dict[str, float]:
        Y = self._Ym
        warp0 = (0.05, 0.02)
        x_prev = None
        for _ in range(10 if self.compensated else 1):
            reg = bilinear_regression(self._s, Y, self._w, model=self.model, warp0=warp0)
            out = self._pick_mapping(reg)
            warp0 = (reg["rho"], reg["xi"])
            if not self.compensated:
                break
            # refer the data to the reference temperature with this circuit, and fit again until the
            # circuit stops changing (a fixed point: the data corrected by the fitted circuit's own
            # temperature effect are fitted by that circuit)
            x = np.array([out[n] for n in self.parameter_names])
            if x_prev is not None and np.all(np.abs(x - x_prev) <= 1e-10 * np.maximum(np.abs(x), 1e-12)):
                break
            x_prev = x
            c = self.full_parameters(x)
            Y_ref = input_admittance(
                self._s, c["R1_total"], c["X1"], c["R2"], c["X2"], c["R0"], c["X0"], c["R2sigma"], c["X3"]
            )[0]
            Y = self._Ym + (Y_ref - self.admittance(x)[0])
        self.last_mapping = out["mapping"]
        return out

    def _pick_mapping(self, reg: dict) -> dict:
        """The free mapping when it is physical and inside the bounds (and X1, X2 are not tied),
        else the tied one."""
        free = reg["free"]
        if not self.tie_x1_x2:
            x = np.array([free[n] for n in self.parameter_names])
            if np.all(np.isfinite(x)) and np.all(x >= self.lower) and np.all(x <= self.upper):
                return free | {"mapping": "free"}
        return reg["tied"] | {"mapping": "tied (X1 = X2)"}



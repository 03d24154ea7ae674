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
from benchmark.problems.admittance import reporting
from benchmark.problems.admittance.circuit import input_admittance, rotor_admittance
from benchmark.problems.admittance.data import AdmittanceData
from benchmark.problems.admittance.initial_models import model_a, model_e
from benchmark.problems.admittance.regression import bilinear_regression
from benchmark.problems.admittance.thermal import TemperatureProfile, estimate_temperatures, measured_temperatures

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
NORMALISATIONS = ("auto", "full_scale", "measured", "instrument")


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
    normalisation : ``full_scale``, ``measured``, ``instrument`` (each of G and B over its standard
        error propagated from the instruments, ``data.sigma_G``, ``data.sigma_B``: a load test) or
        ``auto`` (``instrument`` when the data give standard errors, else ``full_scale``).
    stalled_torque_weight : weight of the stalled-torque term (0: off; needs a torque column).
    temperature_compensation : ``auto`` (on when the data allow it), True or False.
    heat_model : ``auto``, ``losses`` or ``current_squared`` (see the module docstring).
    tie_x1_x2 : search ``X1`` only, with ``X2 = X1``.
    truth : true parameters (the scoring keys of :meth:`estimate`), or None.
    reference_temperature : deg C to refer resistances to (None: the data's, else the start).
    magnetising_factor : per reading, ``Xm(psi_i)/Xm(psi_ref)`` from a no-load series (the
        magnetising branch's parallel reactance is scaled by it, its core-loss conductance kept;
        :mod:`benchmark.problems.admittance.noload`), or None (no saturation modelled).

    Readings at another supply frequency (``data.frequency_ratio`` k) see reactances ``k X`` and
    the magnetising branch's series resistance ``k^2 R0`` (a constant core-loss conductance).
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
        magnetising_factor: np.ndarray | None = None,
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
        if normalisation == "auto":
            normalisation = "instrument" if data.sigma_G is not None else "full_scale"
        if normalisation == "instrument" and data.sigma_G is None:
            raise ConfigError("problem.normalisation: 'instrument' needs a load test (kind: loadtest), whose "
                              "readings carry their standard errors")
        self.normalisation = normalisation
        #: residuals over the readings' stated standard errors: the covariance is (J'J)^-1, not a sandwich
        self.stated_noise = normalisation == "instrument"
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
        # weights of G and B (the same unless the instruments' standard errors are used)
        self._wG = self._wB = self._w
        if normalisation == "instrument":
            self._wG, self._wB = 1.0 / np.asarray(data.sigma_G, float), 1.0 / np.asarray(data.sigma_B, float)
        self._n_res = 2 * len(s)
        kf = data.frequency_ratio
        self._kf = None if kf is None or np.all(np.asarray(kf) == 1.0) else np.asarray(kf, float)
        self._gm = None if magnetising_factor is None else np.asarray(magnetising_factor, float)
        self._k1 = None  # a multiplicative copper factor on R1_total (measured temperatures, no DC value)
        #: set by the set-up: the model choice (benchmark.problems.admittance.model_choice) and the
        #: magnetising curve used, for the record
        self.model_choice = None
        self.magnetising_curve = None

        # temperature compensation
        comp = temperature_compensation
        measured = data.winding_temperature is not None
        can = measured or (data.stator_dc_resistance is not None and data.time is not None)
        self.profile: TemperatureProfile | None = None
        self._comp_note = ""
        if comp == "auto":
            comp = can
            if not can:
                self._comp_note = (
                    "off: the data give no stator_dc_resistance [before, after] or no time column"
                    " (a sweep), or no temperature column (a load test)"
                )
        elif comp is True and not can:
            raise ConfigError(
                "problem.temperature_compensation: true needs 'stator_dc_resistance' [before, after] "
                f"in meta.yaml and a 'time' column in the sweep tables of {data.source}, or a load "
                "test's temperature column"
            )
        elif comp not in (True, False):
            raise ConfigError(f"problem.temperature_compensation: auto, true or false, got {comp!r}")
        if comp and measured:
            self.profile = measured_temperatures(data, reference_temperature)
            self._k = self.profile.factor
            if np.isfinite(self.profile.R1_ref):
                self._dR1 = self.profile.R1_ref * (self._k - 1.0)
            else:
                self._dR1, self._k1 = np.zeros_like(s), self._k
        elif comp:
            self.profile = estimate_temperatures(data, heat_model, reference_temperature)
            self._k = self.profile.factor
            self._dR1 = self.profile.R1_ref * (self._k - 1.0)
        else:
            self._k = np.ones_like(s)
            self._dR1 = np.zeros_like(s)
        self.compensated = bool(comp)
        # R1 referred to the reference temperature: separable from R1sigma only via the DC value
        self.R1_dc: float | None = None
        if self.profile is not None and np.isfinite(self.profile.R1_ref):
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
        R1t = c["R1_total"] + self._dR1 if self._k1 is None else c["R1_total"] * self._k1
        if self._kf is not None or self._gm is not None:
            return self._scaled_admittance(c, R1t)
        with np.errstate(all="ignore"):
            return input_admittance(
                self._s,
                R1t,
                c["X1"],
                c["R2"] * self._k,
                c["X2"],
                c["R0"],
                c["X0"],
                c["R2sigma"],
                c["X3"],
            )

    def _scaled_admittance(self, c, R1t) -> np.ndarray:
        """:meth:`admittance` with readings at other frequencies and a saturating magnetising branch."""
        k = np.ones_like(self._s) if self._kf is None else self._kf
        with np.errstate(all="ignore"):
            Z0 = c["R0"] * k**2 + 1j * c["X0"] * k
            if self._gm is not None:
                Y0 = 1.0 / Z0
                Z0 = 1.0 / (Y0.real + 1j * Y0.imag / self._gm)
            Y2 = rotor_admittance(self._s, c["R2"] * self._k, c["X2"] * k, c["R2sigma"], c["X3"] * k)
            return 1.0 / (R1t + 1j * c["X1"] * k + Z0 / (1.0 + Z0 * Y2))

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
        E = Y - self._Ym
        R = np.concatenate([E.real * self._wG, E.imag * self._wB], axis=1) / np.sqrt(self._n_res)
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
        out["X1+X2"] = out["X1"] + out["X2"]
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
        if "X1" in t and "X2" in t:
            t["X1+X2"] = t["X1"] + t["X2"]
        keys = self.estimate(0.5 * (self.lower + self.upper)).keys()
        return {k: t[k] for k in keys if k in t}

    #: What the cost is measured in (figure labels).
    cost_unit = "S$^2$: mean squared G, B misfit, full scale = 1"

    def plots(self, x, record: dict) -> list:
        """This problem's figures of a run (not yet drawn): see :mod:`benchmark.problems.admittance.figures`."""
        from benchmark.problems.admittance.figures import admittance_plots

        return admittance_plots(self, x, record)

    def describe(self) -> dict:
        """Facts recorded in ``result.json`` (:func:`benchmark.problems.admittance.reporting.describe`)."""
        return reporting.describe(self)

    def quality_warnings(self, x) -> list[str]:
        """The problem's own warnings (:func:`benchmark.problems.admittance.reporting.quality_warnings`)."""
        return reporting.quality_warnings(self, x)

    def identifiability_notes(self) -> list[str]:
        return reporting.identifiability_notes(self)

    # -- the hook used by plugins.lindsay_barton ---------------------------------------------

    def initial_guess(self, kind: str) -> np.ndarray | None:
        """The paper's initial models ``"A"`` or ``"E"`` from the data alone (no cost evaluation),
        clipped into the bounds (:mod:`benchmark.problems.admittance.initial_models`; ``"E"`` sets
        :attr:`last_mapping`). Returns None for an unknown kind."""
        kind = str(kind).upper()
        if kind not in ("A", "E"):
            return None
        vals = model_a(self) if kind == "A" else model_e(self)
        x = np.array([vals[n] for n in self.parameter_names], float)
        span = self.upper - self.lower
        return np.clip(
            np.where(np.isfinite(x), x, 0.5 * (self.lower + self.upper)),
            self.lower + 1e-6 * span,
            self.upper - 1e-6 * span,
        )

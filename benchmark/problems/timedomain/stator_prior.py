"""The stator resistance's prior (``problem.stator_resistance=prior``): the DC resistance measured
between the terminals (meta.yaml ``stator_dc_resistance``) as prior knowledge of Rs, a Gaussian
``Rs ~ N(R_dc, (s R_dc)^2)``, weighed against the data in the same units.

**Spread.** During the record the winding is not at the temperature it had when its DC
resistance was measured: within about 40 K of it (a cold measurement, a motor warm from earlier
runs, or the other way round), taken as two standard deviations: ``sigma_theta = 20 K`` by
default (``problem.stator_prior_spread``). Copper's resistance is proportional to
``234.5 + theta`` (deg C), so ``s = sigma_theta / (234.5 + theta_dc)``, 7.9 % at 20 deg C
(``theta_dc`` from meta.yaml ``winding_temperature``, else 20 deg C).

**Weight.** Prior and data are combined as a posterior would combine them if the data's
information about Rs is what the fit's own standard error says: the HAC sandwich variance ``V``
of Rs (:func:`benchmark.core.uncertainty.hac_covariance_floored`, which grows with the misfit and with
its correlation in time), not ``N`` independent samples. A model that misses the data by ten
times the noise over 36 000 correlated samples would otherwise outweigh any prior by sheer
sample count and move Rs by a factor two unopposed. In the least-squares objective ``sum r^2``
(eq. 14, the polish) the prior adds ``w_ls (Rs - R_dc)^2`` with ``w_ls = (V / A) / (s R_dc)^2``,
``A`` the Rs diagonal of ``(J'J)^-1`` (``V / A`` is the residual variance the data show in the
direction of Rs). In eq. 15's ``sum k |e|`` it adds ``w_1 (Rs - R_dc)^2``, ``w_1 = V / (2 B (s
R_dc)^2)``, ``B`` the Rs diagonal of the inverse of eq. 15's expected Hessian
``sum_c sqrt(2 / pi) / rms_c J_c'J_c`` (each channel's residual spread ``rms_c``). Before any fit
``V / A`` is the noise's (white, at the noise level); :meth:`StatorResistancePrior.calibrate`
sets it from the fit and the result is polished again until it holds (a few rounds).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from benchmark.core.uncertainty import hac_covariance_floored

#: Default one-sigma spread of the winding's temperature during the record about its temperature
#: at the DC measurement, K (``problem.stator_prior_spread``).
DEFAULT_SPREAD_K = 20.0
#: Copper's resistance is proportional to this + theta (deg C).
COPPER_ZERO_C = 234.5
#: Winding temperature taken when meta.yaml gives none, deg C.
DEFAULT_TEMPERATURE_C = 20.0
#: A calibration that changes a weight by less than this share changes nothing.
CALIBRATION_TOLERANCE = 0.1
#: Temperatures a copper winding can have, deg C (meta.yaml's ``winding_temperature`` is checked
#: against them; a resistance that needs a temperature outside them is not the winding's alone).
WINDING_TEMPERATURE_RANGE_C = (-60.0, 250.0)


def copper_temperature(resistance: float, dc: float, winding_temperature: float | None = None) -> float:
    """deg C at which a copper winding measured at ``dc`` ohm at ``winding_temperature`` deg C
    (default 20) has ``resistance`` ohm: ``R / R_dc = (234.5 + theta) / (234.5 + theta_dc)``."""
    theta = DEFAULT_TEMPERATURE_C if winding_temperature is None else float(winding_temperature)
    return float(resistance) / float(dc) * (COPPER_ZERO_C + theta) - COPPER_ZERO_C


def relative_spread(winding_temperature: float | None, spread_k: float = DEFAULT_SPREAD_K) -> float:
    """One-sigma relative spread of the prior: ``spread_k / (234.5 + theta_dc)``."""
    theta = DEFAULT_TEMPERATURE_C if winding_temperature is None else float(winding_temperature)
    return float(spread_k) / (COPPER_ZERO_C + theta)


@dataclass
class StatorResistancePrior:
    """``Rs ~ N(dc, (rel_std dc)^2)`` weighed against the data (see the module docstring).

    dc : ohm; rel_std : relative one-sigma spread; exponent : the cost's (1: eq. 15, 2: eq. 14);
    variance_ratio : ``V / A``, the data's residual variance in the direction of Rs (in the
    units of the least-squares residuals); hessian_ratio : ``V / (2 B)`` for eq. 15.
    """

    dc: float
    rel_std: float
    exponent: int
    variance_ratio: float
    hessian_ratio: float
    calibrated: bool = False

    @classmethod
    def at_noise_level(cls, dc: float, rel_std: float, exponent: int, residual_noise: float) -> StatorResistancePrior:
        """Before a fit: white residuals of std ``residual_noise`` (one least-squares residual,
        ``sqrt(k) sigma``): ``V / A = sigma^2`` and, for eq. 15, ``V / (2 B) = sigma / sqrt(2 pi)``."""
        s = max(float(residual_noise), 1e-300)
        return cls(float(dc), float(rel_std), int(exponent), s**2, s / math.sqrt(2.0 * math.pi))

    @property
    def std(self) -> float:
        """The prior's standard deviation, ohm."""
        return self.rel_std * self.dc

    @property
    def weight_ls(self) -> float:
        """``w_ls``: weight of ``(Rs - dc)^2`` in ``sum r^2``."""
        return self.variance_ratio / self.std**2

    @property
    def weight_cost(self) -> float:
        """Weight of ``(Rs - dc)^2`` in the problem's cost (eq. 14: ``w_ls``; eq. 15: ``w_1``)."""
        return self.weight_ls if self.exponent == 2 else self.hessian_ratio / self.std**2

    def residual(self, rs: np.ndarray) -> np.ndarray:
        """The prior's least-squares residual of each candidate: ``sqrt(w_ls) (Rs - dc)``."""
        return math.sqrt(self.weight_ls) * (np.asarray(rs, float) - self.dc)

    def cost(self, rs: np.ndarray) -> np.ndarray:
        """The prior's term in the problem's cost: ``w (Rs - dc)^2``."""
        return self.weight_cost * (np.asarray(rs, float) - self.dc) ** 2

    def cost_of_residual(self, p: float) -> float:
        """The cost term of a prior residual ``p`` (:meth:`residual`)."""
        return self.weight_cost / self.weight_ls * float(p) ** 2

    def calibrate(self, jac: np.ndarray, res: np.ndarray, groups: np.ndarray, rs_col: int,
                  bandwidth_floor: float = 0.0) -> bool:
        """Set ``V / A`` (and eq. 15's ratio) from the data's Jacobian ``jac`` (rows: the data's
        least-squares residuals ``res``, channel labels ``groups``; no prior row) at the fit;
        True when a weight changed by more than :data:`CALIBRATION_TOLERANCE`."""
        cov, _ = hac_covariance_floored(jac, res, groups=groups, floor=bandwidth_floor)
        V = float(cov[rs_col, rs_col])
        A = float(np.linalg.pinv(jac.T @ jac)[rs_col, rs_col])
        H = sum(math.sqrt(2.0 / math.pi) / max(math.sqrt(float(np.mean(res[groups == g] ** 2))), 1e-300)
                * jac[groups == g].T @ jac[groups == g] for g in np.unique(groups))
        B = float(np.linalg.pinv(H)[rs_col, rs_col])
        if not (math.isfinite(V) and V > 0 and A > 0 and B > 0):
            return False
        new_ls, new_1 = V / A, V / (2.0 * B)
        changed = (abs(new_ls / self.variance_ratio - 1.0) > CALIBRATION_TOLERANCE
                   or abs(new_1 / self.hessian_ratio - 1.0) > CALIBRATION_TOLERANCE)
        self.variance_ratio, self.hessian_ratio, self.calibrated = new_ls, new_1, True
        return changed

    def describe(self) -> dict:
        return {"stator_dc_resistance": self.dc, "relative_std": self.rel_std, "std_ohm": self.std,
                "weight": "HAC variance of Rs at the fit" if self.calibrated else "noise level (not calibrated)",
                "residual_variance_in_Rs_direction": self.variance_ratio}


class StatorPriorTerms:
    """The prior's part of the time-domain problem (a mixin): its term in the cost and the
    residuals, its calibration at a fit (:func:`benchmark.core.review.review` calls
    :meth:`calibrate`) and what it cost (:meth:`explain`). Expects the problem's
    ``stator_resistance``, ``rs_dc``, ``dataset``, ``exponent``, ``weights``, ``parameter_names``,
    :meth:`channel_noise`, ``residuals_batch`` and ``residual_layout``."""

    def _init_prior(self, spread_k: float) -> None:
        self.prior_spread_k = float(spread_k)
        self._prior: StatorResistancePrior | None = None
        self._prior_off = False  # True while the data alone are fitted (explain)
        self.prior_by_default = False  # set by problem_from_dataset: auto made it a prior

    @property
    def prior_active(self) -> bool:
        return self.stator_resistance == "prior" and not self._prior_off

    @property
    def prior(self) -> StatorResistancePrior:
        """The prior (made on first use, weighed at the noise level until :meth:`calibrate`)."""
        if self._prior is None:
            var = [self.weights[c] * est.std**2 for per_record in self.channel_noise()
                   for c, est in enumerate(per_record) if est is not None and self.weights[c] > 0]
            s = math.sqrt(float(np.mean(var))) if var else 1e-3
            self._prior = StatorResistancePrior.at_noise_level(
                self.rs_dc, relative_spread(getattr(self.dataset, "winding_temperature", None), self.prior_spread_k),
                self.exponent, s)
        return self._prior

    def _rs(self, X) -> np.ndarray:
        return np.atleast_2d(np.asarray(X, float))[:, self.parameter_names.index("Rs")]

    def prior_cost(self, X) -> np.ndarray:
        return self.prior.cost(self._rs(X))

    def prior_residual(self, X) -> np.ndarray:
        return self.prior.residual(self._rs(X))

    def calibrate(self, x) -> bool:
        """Weigh the prior by the data's information about Rs at the fit ``x`` (the HAC variance,
        :meth:`StatorResistancePrior.calibrate`); True when its weight changed."""
        from benchmark.core.quality import jacobian

        if not self.prior_active:
            return False
        with np.errstate(all="ignore"):
            r0, J = jacobian(self, np.asarray(x, float))
        layout = [seg for seg in self.residual_layout() if seg[0] != "Rs prior"]
        m = layout[-1][2]
        groups = np.empty(m, dtype=int)
        for g, (_, a, b) in enumerate(layout):
            groups[a:b] = g
        J, r0 = J[:m], r0[:m]
        live = np.all(np.isfinite(J), axis=1) & np.isfinite(r0) & (np.any(J != 0, axis=1) | (r0 != 0))
        return self.prior.calibrate(J[live], r0[live], groups[live], self.parameter_names.index("Rs"),
                                    self.hac_bandwidth_floor())

    def explain(self, x, polish_budget: int) -> tuple[list[str], dict | None]:
        """What the prior did at the fit ``x``: the data alone fitted locally from ``x`` (least
        squares without the prior, to its end) give Rs and each channel's misfit without it. Returns the lines the
        result prints and the record (None without a prior)."""
        if not self.prior_active:
            return [], None
        from benchmark.core.quality import fit_quality
        from benchmark.core.review import least_squares_end

        x = np.asarray(x, float)
        self._prior_off = True
        try:
            x_free, evaluations = least_squares_end(self, x, polish_budget)
            q_free = fit_quality(self, x_free)
        finally:
            self._prior_off = False
        q = fit_quality(self, x)
        rs, rs_free = float(self._rs(x)[0]), float(self._rs(x_free)[0])
        p = self.prior
        theta = getattr(self.dataset, "winding_temperature", None)
        at = f" at {theta:g} C" if theta is not None else ""
        misfit = ", ".join(f"{k} {v['ratio']:.4g} (without it {q_free[k]['ratio']:.4g})" for k, v in q.items()
                           if k in q_free)
        default = (" (the default where meta.yaml gives stator_dc_resistance; problem.stator_resistance=free "
                   "leaves Rs to the data)" if getattr(self, "prior_by_default", False) else "")
        line = (f"Rs prior{default}: N({p.dc:.4g} ohm, {100 * p.rel_std:.1f} %) from the DC resistance{at}, the "
                f"spread a standard deviation of {self.prior_spread_k:g} K in the winding's temperature "
                f"(problem.stator_prior_spread), weighed by the data's own uncertainty of Rs: Rs = {rs:.4g} ohm "
                f"({100 * (rs / p.dc - 1):+.1f} % from DC), the data alone {rs_free:.4g} ohm "
                f"({100 * (rs_free / p.dc - 1):+.1f} %). What it cost in misfit (RMS / noise): {misfit}")
        record = {**p.describe(), "Rs": rs, "Rs_data_alone": rs_free, "fit_quality_data_alone": q_free,
                  "evaluations": evaluations}
        return [line], record

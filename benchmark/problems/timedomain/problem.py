"""The time-domain identification problem of Alonge et al. (the paper).

Cost (eqs. 13-15), summed over every start-up record of the data set::

    f = sum_j ka e(i_a,j) + kb e(i_b,j) + kw e(w_j),  e(x) = |x_meas - x_sim|^exponent

with ``exponent`` 1 (eq. 15) or 2 (eq. 14); ``w`` is the mechanical speed in rad/s. Current
samples the conditioning masked (``StartupRecord.weight`` False: clipped probes, the switching
window of a contactor) are left out of the sum, the residuals, the fit quality and the standard
errors; the model is simulated through them.

Searched parameters: ``Rs, Ls, Le, Rr, J`` when a stop record fixes ``tau_m`` and ``fc/J``
(then ``fv = J/tau_m`` and ``fc = J*(fc/J)`` follow for each candidate); ``J`` is dropped when
the inertia is known; with no stop record ``fv`` and ``fc`` are searched too (less precisely:
they then come from the start-up alone).
"""

from __future__ import annotations

import warnings

import numpy as np

from benchmark.core.errors import ConfigError, ImbenchWarning
from benchmark.core.problem import Problem
from benchmark.problems.timedomain.bounds import (  # noqa: F401  (check_config: the harness's hook)
    check_config,
    choose_bounds,
    derive_bounds,
)
from benchmark.problems.timedomain.data import StartupDataset
from benchmark.problems.timedomain.filters import zero_phase_lowpass
from benchmark.problems.timedomain.frames import phasor_speed
from benchmark.problems.timedomain.mechanical import MechanicalEstimate, fit_free_stop
from benchmark.problems.timedomain.motor import PARAMETER_NAMES, PARAMETER_UNITS, coefficients
from benchmark.problems.timedomain.noise import record_noise, supply_frequency_of
from benchmark.problems.timedomain.settings import WEIGHT_KEYS, TimeDomainSettings
from benchmark.problems.timedomain.simulation import hold_is_linear, startup_cost_batch, startup_outputs_batch
from benchmark.problems.timedomain.speed_filter import UnstatedFilter, speed_read_through, unstated_filter
from benchmark.problems.timedomain.stator_prior import DEFAULT_SPREAD_K, StatorPriorTerms
from benchmark.problems.timedomain.switch_on_flux import SwitchOnFlux
from benchmark.problems.timedomain.true_parameters import (  # noqa: F401 (stored run configurations name them here)
    read_truth_document,
    read_truth_for_scoring,
)


class TimeDomainProblem(SwitchOnFlux, StatorPriorTerms, Problem):
    """Start-up record fit. See the module docstring for the cost and the searched set.

    Parameters
    ----------
    dataset : the (conditioned) data set.
    lower, upper : bounds of the searched parameters, in :attr:`parameter_names` order.
    mechanical : free-stop estimate fixing ``tau_m`` and ``fc/J``, or None (then ``fv``, ``fc``
        are searched, or held at ``held_friction``: (N m s/rad, N m)).
    inertia : known inertia (kg m^2), or None to search ``J``.
    exponent : 1 (eq. 15) or 2 (eq. 14).
    weights : (ka, kb, kw). The speed weight is set to 0 when no record has a speed (a record
        without a speed sensor has ``speed`` all NaN; those NaN are replaced by 0 in the arrays).
    truth : true parameters for scoring, or None.
    stator_resistance : ``free`` (searched), ``prior`` (searched, with the DC value as a Gaussian
        prior weighed against the data: :mod:`benchmark.problems.timedomain.stator_prior`) or
        ``fixed`` (not searched: held at the DC value). ``prior`` and ``fixed`` need
        ``dataset.stator_dc_resistance``.
    prior_spread : K, one-sigma spread of the winding's temperature during the record about its
        temperature at the DC measurement (the prior's width).
    """

    name = "timedomain"
    #: Units of the parameters (messages and report).
    units = PARAMETER_UNITS

    def __init__(self, dataset: StartupDataset, lower, upper, mechanical: MechanicalEstimate | None = None,
                 inertia: float | None = None, exponent: int = 1, weights=(1.0, 1.0, 0.5),
                 truth: dict | None = None, stator_resistance: str = "free",
                 held_friction: tuple[float, float] | None = None, prior_spread: float = DEFAULT_SPREAD_K):
        if exponent not in (1, 2):
            raise ConfigError(f"problem.cost.exponent: must be 1 (eq. 15) or 2 (eq. 14), got {exponent}")
        self.dataset = dataset
        self.mechanical = mechanical
        self.inertia = inertia
        self.exponent = int(exponent)
        self.weights = np.asarray(weights, dtype=float)
        if self.weights.shape != (3,) or np.any(self.weights < 0) or not np.any(self.weights > 0):
            raise ConfigError(f"problem.cost.weights: need three non-negative weights, got {weights}")
        self.speed_measured = any(np.any(np.isfinite(r.speed)) for r in dataset.startups)
        if not self.speed_measured:
            self.weights = self.weights.copy()
            self.weights[2] = 0.0
            if not np.any(self.weights > 0):
                raise ConfigError("problem.cost.weights: the records have no speed and both current weights are 0")
        if stator_resistance not in ("free", "prior", "fixed"):
            raise ConfigError(f"problem.stator_resistance: must be free, prior or fixed, got {stator_resistance!r}")
        self.stator_resistance = stator_resistance
        self.rs_dc = getattr(dataset, "stator_dc_resistance", None)
        if stator_resistance != "free" and not (self.rs_dc is not None and self.rs_dc > 0):
            raise ConfigError(f"problem.stator_resistance={stator_resistance}: needs the DC stator resistance "
                              "(stator_dc_resistance in the data set's meta.yaml); use problem.stator_resistance=free")
        names = [] if stator_resistance == "fixed" else ["Rs"]
        names += ["Ls", "Le", "Rr"]
        if inertia is None:
            names.append("J")
        self.held_friction = None if mechanical is not None or held_friction is None else tuple(held_friction)
        if mechanical is None and self.held_friction is None:
            names += ["fv", "fc"]
        self.parameter_names = tuple(names)
        self.lower = np.asarray(lower, dtype=float)
        self.upper = np.asarray(upper, dtype=float)
        self.truth = truth
        self.check_bounds()
        self._linear = hold_is_linear(dataset.input_hold)
        self._records = [
            (np.ascontiguousarray(r.v_alpha), np.ascontiguousarray(r.v_beta), np.ascontiguousarray(r.i_alpha),
             np.ascontiguousarray(r.i_beta),
             np.ascontiguousarray(r.speed if self.speed_measured else np.zeros_like(r.i_alpha)))
            for r in dataset.startups
        ]
        # Current samples the conditioning masked (StartupRecord.weight False: clipped probes, the
        # switching window): they add nothing to the cost and their residuals are 0. None: all count.
        self._current_used = [None if r.weight is None else np.ascontiguousarray(np.asarray(r.weight, bool))
                              for r in dataset.startups]
        self._noise = None  # per-channel noise estimates, made on first use (see channel_noise)
        # what the problem was made from (problem_from_dataset): settings and the loaded data set
        self.settings: TimeDomainSettings | None = None
        self.loaded_dataset: StartupDataset | None = None
        self._init_prior(prior_spread)
        self._init_switch_on_flux()
        self.speed_lag = float(dataset.speed_filter or 0.0)  # s: the speed channel's stated filter

    # -- parameter vectors -------------------------------------------------------------
    def full_parameters(self, X: np.ndarray) -> np.ndarray:
        """Searched vectors (n, n_var) -> physical parameters (n, 7) in PARAMETER_NAMES order."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        col = {n: X[:, k] for k, n in enumerate(self.parameter_names)}
        if "Rs" not in col:  # stator_resistance=fixed
            col["Rs"] = np.full(len(X), float(self.rs_dc))
        J = col["J"] if "J" in col else np.full(len(X), self.inertia)
        if self.mechanical is not None:
            fv = J / self.mechanical.tau_m
            fc = J * self.mechanical.fc_over_J
        elif self.held_friction is not None:
            fv, fc = (np.full(len(X), v) for v in self.held_friction)
        else:
            fv, fc = col["fv"], col["fc"]
        return np.column_stack([col["Rs"], col["Ls"], col["Le"], col["Rr"], J, fv, fc])

    def estimate(self, x: np.ndarray) -> dict[str, float]:
        theta = self.full_parameters(x)[0]
        return {n: float(v) for n, v in zip(PARAMETER_NAMES, theta, strict=True)}

    # -- cost ------------------------------------------------------------------------
    def evaluate(self, X: np.ndarray) -> np.ndarray:
        if self.speed_lag > 0.0:  # a stated speed filter: the cost of the filtered outputs (the compiled
            costs = np.array([self.cost_from_residuals(r) for r in self.residuals_batch(X)])  # cost reads it raw)
            return np.where(np.isfinite(costs), costs, np.inf)
        coef = coefficients(self.full_parameters(X), self.dataset.pole_pairs)
        total = np.zeros(len(coef))
        for (v_a, v_b, i_a, i_b, w), used in zip(self._records, self._current_used, strict=True):
            total += startup_cost_batch(coef, v_a, v_b, self._linear, self.dataset.sample_time, i_a, i_b, w,
                                        float(self.dataset.pole_pairs), self.weights, self.exponent, used)
        if self.prior_active:
            total = total + self.prior_cost(X)
        return total

    # -- noise, fit quality and warnings (benchmark.core.quality) ----------------------------
    def channel_noise(self) -> list[list]:
        """Per record, the noise estimate (:class:`benchmark.core.noise_estimates.NoiseEstimate`) of
        i_alpha, i_beta and speed (None where not measured), from the data alone: the one estimate
        of :func:`benchmark.problems.timedomain.noise.record_noise` that the diagnosis uses too (a
        quiet pre-trigger, else the steady state's supply harmonics with drifting amplitudes;
        quantised channels at least ``q / sqrt(12)``; coloured noise and the estimate's own
        uncertainty allowed for)."""
        if self._noise is None:
            ds = self.dataset
            per_record = [record_noise(r, ds.supply_frequency, ds.speed_filter)[0] for r in ds.startups]
            self._noise = [[noise.get(c) for c in WEIGHT_KEYS] for noise in per_record]
        return self._noise

    def hac_bandwidth_floor(self) -> float:
        """Smallest Bartlett bandwidth (samples) of the HAC covariance: one supply period
        (see :mod:`benchmark.core.quality`); 0 when the frequency is unknown."""
        v_a, v_b = self._records[0][0], self._records[0][1]
        n = len(v_a)
        f0 = _supply_frequency(v_a[int(0.75 * n):], v_b[int(0.75 * n):], self.dataset.sample_time) or \
            self.dataset.supply_frequency
        return float(1.0 / (f0 * self.dataset.sample_time)) if f0 and f0 > 0 else 0.0

    def residual_layout(self) -> list[tuple[str, int, int]]:
        """(channel, start, stop) of each contiguous segment of :meth:`residuals_batch` rows."""
        out, offset = [], 0
        for j, rec in enumerate(self._records):
            m = len(rec[2])
            for c, key in enumerate(WEIGHT_KEYS):
                out.append((key if len(self._records) == 1 else f"{key}[{j}]", offset + c * m, offset + (c + 1) * m))
            offset += 3 * m
        if self.prior_active:
            out.append(("Rs prior", offset, offset + 1))
        return out

    def noise_levels(self, x) -> list[dict]:
        """Per record, ``{channel: NoiseEstimate}`` of the residual at ``x``: :meth:`channel_noise`,
        and for measured continuous voltages (``input_hold: linear``) each channel raised by the
        voltage's own noise carried through the model at ``x``
        (:func:`benchmark.problems.timedomain.voltage_noise.with_propagated_voltage_noise`, as
        the diagnosis does: the motor saw the clean voltage, the model the noisy one)."""
        levels = [{k: est for k, est in zip(WEIGHT_KEYS, per_record, strict=True) if est is not None}
                  for per_record in self.channel_noise()]
        if not self._linear:
            return levels
        from benchmark.problems.timedomain.voltage_noise import with_propagated_voltage_noise

        coef = coefficients(self.full_parameters(np.asarray(x, float)[None, :]), self.dataset.pole_pairs)
        out = []
        for noise, rec, (v_a, v_b, *_) in zip(levels, self.dataset.startups, self._records, strict=True):
            def simulate(va, vb, noise=noise):
                y = speed_read_through(startup_outputs_batch(coef, np.ascontiguousarray(va), np.ascontiguousarray(vb),
                                                             True, self.dataset.sample_time,
                                                             float(self.dataset.pole_pairs)),
                                       self.speed_lag, self.dataset.sample_time)[0]
                return {k: y[c] for c, k in enumerate(WEIGHT_KEYS) if k in noise}

            speed = rec.speed if rec.has_speed else None
            out.append(with_propagated_voltage_noise(noise, simulate, rec.t, v_a, v_b, rec.i_alpha, rec.i_beta,
                                                     speed, float(self.dataset.supply_frequency or
                                                                  supply_frequency_of(rec.t, v_a, v_b)))[0])
        return out

    def fit_channels(self, x) -> list[tuple]:
        """(channel, held-in residual ``measured - simulated`` in A or rad/s, noise estimate of
        :meth:`noise_levels`) of every measured, weighted channel at ``x``."""
        sims = self.simulate(np.asarray(x, float)[None, :])
        out = []
        for j, (sim, rec, noise, used) in enumerate(zip(sims, self._records, self.noise_levels(x),
                                                        self._current_used, strict=True)):
            for c, key in enumerate(WEIGHT_KEYS):
                if self.weights[c] == 0 or key not in noise:
                    continue
                r = rec[2 + c] - sim[0, c]
                if c < 2 and used is not None:  # masked current samples are not part of the fit
                    r = r[used]
                out.append((key if len(self._records) == 1 else f"{key}[{j}]", r, noise[key]))
        return out

    def second_look(self, x, identify, seed: int) -> dict | None:
        """The identification's second look (:func:`benchmark.core.review.review`, called where the
        fit at ``x`` misses the data): the stop record's check
        (:func:`benchmark.problems.timedomain.stop_record.stop_record_check`, the diagnosis's
        too). Returns ``{"record", "lines", "problem", "identification"}``, the last two the
        start-up-alone problem and its identification (``identify(problem, seed=...)``) when the
        stop record is set aside, else None; None when there is no check to make."""
        from types import SimpleNamespace

        from benchmark.problems.timedomain.stop_record import stop_record_check, stop_record_lines

        if self.settings is None:
            return None
        check = stop_record_check(self.settings, self.loaded_dataset, self, SimpleNamespace(x=np.asarray(x, float)),
                                  identify, seed)
        if check is None:
            return None
        record, alone, ident_alone = check
        aside = not record["used"]
        alone.truth = self.truth  # (scoring only)
        return {"record": record, "lines": stop_record_lines(record, "the identification uses"),
                "problem": alone if aside else None, "identification": ident_alone if aside else None}

    #: Rs departing from the DC resistance by more than this (relative) is reported.
    RS_DC_TOLERANCE = 0.20

    def quality_warnings(self, x) -> list[str]:
        """This problem's own warnings at ``x``: Rs against the DC resistance, speed not measured, a
        speed filter the record does not state (:meth:`unstated_speed_filter`)."""
        out = []
        if self.rs_dc is not None and self.rs_dc > 0 and self.stator_resistance != "fixed":
            rs = self.estimate(x)["Rs"]
            dev = rs / self.rs_dc - 1.0
            if abs(dev) > self.RS_DC_TOLERANCE:
                temp = getattr(self.dataset, "winding_temperature", None)
                at = f" at {temp:g} C" if temp is not None else ""
                advice = ("even with the DC value as its prior: the data pull it there (the model misses the data, "
                          "or the winding's temperature is far from the DC measurement's); add "
                          "problem.stator_resistance=fixed to hold it, and diagnose the data"
                          if self.stator_resistance == "prior" else
                          "the fit may be in a wrong minimum or the model misses the data; add "
                          "problem.stator_resistance=prior (or fixed) to the command, and diagnose the data")
                out.append(f"Rs = {rs:.4g} ohm departs from the DC resistance {self.rs_dc:.4g} ohm{at} "
                           f"(meta.yaml stator_dc_resistance) by {100 * dev:+.0f} % (more than "
                           f"{100 * self.RS_DC_TOLERANCE:.0f} %) {advice}")
        hint = self.unstated_speed_filter(x)
        return out + ([hint.warning] if hint else [])

    def unstated_speed_filter(self, x) -> UnstatedFilter | None:
        """A filter the record does not state but the speed reads through at ``x``
        (:func:`~.speed_filter.unstated_filter`), or None: also None where the record states
        one, measures no speed or the cost does not weigh it."""
        if self.speed_measured and self.weights[2] > 0 and not self.speed_lag:
            return unstated_filter(self, np.asarray(x, float))
        return None

    def simulate(self, X: np.ndarray, speed_lags: np.ndarray | None = None) -> list[np.ndarray]:
        """Simulated (i_alpha, i_beta, speed) per record: a list of (n, 3, N) arrays, the speed read
        through the stated filter (``speed_lags``, s: each row's own instead)."""
        coef = coefficients(self.full_parameters(X), self.dataset.pole_pairs)
        h, p = self.dataset.sample_time, float(self.dataset.pole_pairs)
        lags = self.speed_lag if speed_lags is None else speed_lags
        return [speed_read_through(startup_outputs_batch(coef, v_a, v_b, self._linear, h, p), lags, h)
                for v_a, v_b, *_ in self._records]

    def residuals_batch(self, X: np.ndarray, speed_lags: np.ndarray | None = None) -> np.ndarray:
        """Weighted residuals ``sqrt(k) (x_meas - x_sim)`` of each candidate: (n, 3*N_total),
        0 at the masked current samples. Their sum of squares is the eq. 14 cost with the same
        weights and mask. ``speed_lags``: as for :meth:`simulate`."""
        parts = []
        sw = np.sqrt(self.weights)[None, :, None]
        for sim, (_, _, i_a, i_b, w), used in zip(self.simulate(X, speed_lags), self._records, self._current_used,
                                                  strict=True):
            meas = np.stack([i_a, i_b, w])[None]
            e = sw * (meas - sim)
            if used is not None:  # masked current samples: residual 0 (no cost, no Jacobian row)
                e[:, :2, ~used] = 0.0
            parts.append(e.reshape(len(sim), -1))
        if self.prior_active:
            parts.append(self.prior_residual(X)[:, None])
        r = np.concatenate(parts, axis=1)
        return np.where(np.isfinite(r), r, np.nan)

    def residuals(self, x: np.ndarray) -> np.ndarray:
        return self.residuals_batch(np.asarray(x, float)[None, :])[0]

    def cost_from_residuals(self, r: np.ndarray) -> float:
        if self.exponent == 2:
            return float(r @ r)
        # r = sqrt(k) e record by record (channel-major), so k |e| = sqrt(k) |r|
        total = 0.0
        offset = 0
        for _, _, i_a, *_ in self._records:
            m = len(i_a)
            block = r[offset:offset + 3 * m].reshape(3, m)
            total += float(np.sqrt(self.weights) @ np.abs(block).sum(axis=1))
            offset += 3 * m
        if self.prior_active:
            total += self.prior.cost_of_residual(r[offset])
        return total

    @property
    def cost_unit(self) -> str:
        """What the cost is measured in (figure labels)."""
        return "eq. 15: weighted |error|, A and rad/s" if self.exponent == 1 else "eq. 14: weighted squared error"

    def plots(self, x, record: dict) -> list:
        """This problem's figures of a run (not yet drawn): see :mod:`benchmark.problems.timedomain.figures`."""
        from benchmark.problems.timedomain.figures import timedomain_plots

        return timedomain_plots(self, x, record)

    def describe(self) -> dict:
        d = {
            "data": self.dataset.folder or "synthetic (in memory)",
            "records": len(self._records),
            "samples": int(sum(len(r[0]) for r in self._records)),
            "sample_time": self.dataset.sample_time,
            "pole_pairs": int(self.dataset.pole_pairs),
            "input_hold": self.dataset.input_hold,
            "conditioning": list(self.dataset.conditioning),
            "cost": {"exponent": self.exponent, "weights": dict(zip(WEIGHT_KEYS, self.weights.tolist(), strict=True))},
        }
        if self.mechanical is not None:
            m = self.mechanical
            d["mechanical"] = {"case": m.case, "tau_m": m.tau_m, "fc_over_J": m.fc_over_J, "w0": m.w0,
                               "t_free": m.t_free}
        if self.inertia is not None:
            d["inertia_known"] = self.inertia
        if self.held_friction is not None:
            d["held_friction"] = dict(zip(("fv", "fc"), self.held_friction, strict=True))
        if not self.speed_measured:
            d["speed"] = "not measured (speed weight set to 0)"
        if self.nuisance_names:
            d["switch_on_flux"] = {n: float(v) for n, v in zip(self.nuisance_names, self.nuisance_values,
                                                                strict=True)}
        d["stator_resistance"] = self.stator_resistance
        if self.rs_dc is not None:
            d["stator_dc_resistance"] = self.rs_dc
            if self.stator_resistance == "fixed":
                d["Rs_fixed"] = float(self.rs_dc)
        return d


def _supply_frequency(v_a, v_b, dt: float) -> float | None:
    """Electrical frequency (Hz) from the rotation of the voltage phasor, or None."""
    w = abs(phasor_speed(v_a, v_b, np.arange(len(v_a)) * dt))
    return w / (2 * np.pi) if w > 0 else None


# -- set-up from typed settings ---------------------------------------------------------
def setup_problem(settings: TimeDomainSettings, dataset: StartupDataset, truth_doc: dict | None) -> TimeDomainProblem:
    """The problem for a data set (``truth_doc``: the synthetic truth document, read only for
    scoring; None for measured data)."""
    truth = None if truth_doc is None else truth_doc.get("parameters")
    return problem_from_dataset(settings, dataset, truth)


def problem_from_dataset(settings: TimeDomainSettings, ds: StartupDataset, truth: dict | None) -> TimeDomainProblem:
    """Conditioning, mechanical pre-identification from the stop record, bounds, and the problem."""
    loaded = ds
    ds = condition(ds, speed_filter=settings.speed_filter)
    mechanical = None
    if ds.stops:
        stop = ds.stops[0]
        mechanical = fit_free_stop(stop.t, stop.speed, case=settings.friction_case, source=stop.source)
    inertia = ds.inertia if ds.inertia is not None else settings.known_inertia
    held = settings.held_friction
    if held is not None:
        warnings.warn(ImbenchWarning(
            "problem.held_friction ignored: the stop record's pre-identification fixes the friction" if mechanical
            else f"friction held at the stated assumption fv = {held[0]:g} N m s/rad, fc = {held[1]:g} N m "
                 "(problem.held_friction), not searched: J absorbs any difference from the true friction, "
                 "which its standard error does not include"),
            stacklevel=2)
    rs_mode = settings.stator_resistance
    if rs_mode == "auto":  # the DC resistance in meta.yaml makes the prior the default
        rs_mode = "prior" if ds.stator_dc_resistance else "free"
    names = ([] if rs_mode == "fixed" else ["Rs"]) + ["Ls", "Le", "Rr"] + \
        (["J"] if inertia is None else []) + ([] if mechanical or held is not None else ["fv", "fc"])
    bounds = choose_bounds(settings, names, ds)
    problem = TimeDomainProblem(
        ds,
        lower=[bounds[n][0] for n in names],
        upper=[bounds[n][1] for n in names],
        mechanical=mechanical,
        inertia=inertia,
        exponent=settings.exponent,
        weights=list(settings.weights),
        truth=truth,
        stator_resistance=rs_mode,
        held_friction=held,
        prior_spread=settings.stator_prior_spread,
    )
    problem.settings, problem.loaded_dataset = settings, loaded
    problem.prior_by_default = settings.stator_resistance == "auto" and rs_mode == "prior"
    return problem


def condition(ds: StartupDataset, speed_filter: bool) -> StartupDataset:
    """Paper conditioning of the start-up speed (optional, docs/time_domain.md): zero-phase low-pass."""
    if not speed_filter:
        return ds
    from dataclasses import replace

    return replace(ds, startups=[replace(r, speed=zero_phase_lowpass(r.speed, ds.sample_time))
                                 for r in ds.startups])

"""Sim-to-real gap diagnosis for the slip sweep (the admittance problem).

1. Identify the base model: the 6-parameter circuit with ``X1 = X2`` (the effect catalogue),
   i.e. ``R1t, X, R2, R0, X0``, by the Sanathanan-Koerner regression of its bilinear form
   (the "E" route, :func:`benchmark.problems.admittance.problem.bilinear_regression`) and a least-squares
   polish. No temperature compensation: a warming is a candidate effect, not part of the base.
2. Estimate the noise of G and B from the data (differences of the base residual along each
   sweep: a model error is smooth in slip, noise is not), and divide every residual by it.
3. Localise the gap: shares of the residual energy by slip region (braking ``s > 1``,
   motoring ``s_near <= s <= 1``, near synchronism ``|s| < s_near``, generating
   ``s <= -s_near``), by component (G, B), by voltage level and by sweep direction.
4. Fit every candidate augmentation (base + one effect of :mod:`benchmark.problems.admittance.effects`)
   from the base fit, and score it by

   * the **held-out** reduction of the misfit: each fold is fitted on the rest of the data
     and scored on the fold. Folds: each **sweep table** when there are several (one voltage
     level's up- or down-sweep: the held-out table differs from the fitted ones in acquisition
     time, which is what tells a warming, and, when a level has a single table, in voltage,
     which is what tells saturation and core loss); else **interleaved readings** (even/odd
     along the sweep: only a guard against fitting noise). Leaving a whole voltage level out
     was tried first and dropped: a saturation curve that is steep near the top level cannot
     be extrapolated from the lower levels, so the right augmentation failed its held-out test;
   * the in-sample reduction, and the information criterion ``delta chi^2/2 + k ln n``
     (``k`` extra parameters, ``n`` residuals; < 0 earns the parameters).
5. Verdict: the candidate with the largest held-out reduction among those that earn their
   parameters and remove at least ``min_heldout_reduction`` of the held-out misfit (and, when
   ``min_gap`` > 0, when the base leaves a held-out gap above it, chi^2 per residual; off by
   default: with a few hundred readings the estimated noise is only good to about 10 %, and
   the criterion is the sharper test); otherwise ``none``.

It never reads ``truth.yaml``: data sets are loaded by
:func:`benchmark.problems.admittance.data.load_admittance`, which reads ``meta.yaml`` and the sweep
tables only; the synthetic in-memory route discards the truth document at once.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass

import numpy as np
from scipy.optimize import least_squares

from benchmark.problems.admittance.data import AdmittanceData
from benchmark.problems.admittance.effects import AdmittanceEffect
from benchmark.problems.admittance.problem import bilinear_regression
from benchmark.problems.admittance.sweep_circuit import SweepCircuit, SweepContext, heat_profile

BASE_NAMES = ("R1t", "X", "R2", "R0", "X0")
REGIONS = ("braking", "motoring", "near_synchronism", "generating")


@dataclass
class AdmittanceDiagnosisSettings:
    """Knobs of the sweep diagnosis (``conf/diagnose.yaml``, block ``admittance_diagnosis``).

    min_gap : optional gate, base held-out chi^2 per residual (1 = noise); 0 = off (default).
    min_heldout_reduction : share of the held-out misfit a candidate must remove.
    explained_share, partly_share : shares of the excess held-out misfit (above the noise)
        separating ``explained`` / ``partly_explained`` / ``unexplained`` (:func:`verdict_contract`).
    fit_evaluations : evaluation limit of each local least-squares fit.
    near_synchronism : ``s_near``, the half-width of the near-synchronism region (slip).
    noise : the noise standard deviation of G and B (S) when known; null: estimated.
    noise_floor : lower bound of the estimated noise, as a fraction of the full scale.
    """

    min_gap: float = 0.0
    explained_share: float = 0.9
    partly_share: float = 0.3
    min_heldout_reduction: float = 0.05
    fit_evaluations: int = 300
    near_synchronism: float = 0.12
    noise: float | None = None
    noise_floor: float = 1e-5


# ----------------------------------------------------------------------------- data


@dataclass
class SweepData:
    """The readings of a sweep data set prepared for the diagnosis."""

    s: np.ndarray
    V: np.ndarray
    Y: np.ndarray
    sweep: np.ndarray
    level: np.ndarray  # index of the voltage level of each reading
    levels: np.ndarray  # the voltage levels, V
    time: np.ndarray | None
    full_scale: float
    sigma: float = 1.0

    @classmethod
    def from_data(cls, d: AdmittanceData) -> SweepData:
        V = np.asarray(d.voltage, float)
        rounded = np.round(V, 3)
        levels, level = np.unique(rounded, return_inverse=True)
        # voltage levels that differ by less than 2 % are one level (a regulated supply's drift)
        merged = [0]
        for k in range(1, len(levels)):
            merged.append(merged[-1] + (levels[k] > 1.02 * levels[k - 1]))
        merged = np.asarray(merged)
        level = merged[level]
        levels = np.array([float(np.mean(V[level == j])) for j in range(int(level.max()) + 1)])
        sweep = np.asarray(d.sweep if d.sweep is not None else np.zeros(d.n, int))
        fs = float(d.full_scale_admittance or np.max(np.abs(d.Y)))
        return cls(
            s=np.asarray(d.slip, float),
            V=V,
            Y=np.asarray(d.Y),
            sweep=sweep,
            level=level,
            levels=levels,
            time=None if d.time is None else np.asarray(d.time, float),
            full_scale=fs,
        )

    @property
    def n(self) -> int:
        return len(self.s)

    def folds(self) -> tuple[str, list[np.ndarray]]:
        """Held-out folds (masks over the readings) and what they are: each sweep table (a
        voltage level's up- or down-sweep) when there are several, else interleaved readings."""
        tables = np.unique(self.sweep)
        if len(tables) >= 2:
            return "sweep_table", [self.sweep == k for k in tables]
        idx = np.arange(self.n)
        return "interleaved", [idx % 2 == 0, idx % 2 == 1]

    def regions(self, s_near: float) -> dict[str, np.ndarray]:
        s = self.s
        return {
            "braking": s > 1.0,
            "motoring": (s >= s_near) & (s <= 1.0),
            "near_synchronism": np.abs(s) < s_near,
            "generating": s <= -s_near,
        }


def noise_estimate(data: SweepData, residual: np.ndarray, floor: float) -> dict[str, float]:
    """Standard deviation of the noise on G and on B (S) from the base residual: within each sweep
    table, in slip order, third differences (a smooth model error is suppressed, white noise has
    variance ``20 sigma^2`` there), robustly through the median absolute value."""
    out = {}
    for name, r in (("G", residual.real), ("B", residual.imag)):
        d = []
        for k in np.unique(data.sweep):
            m = np.flatnonzero(data.sweep == k)
            m = m[np.argsort(data.s[m], kind="stable")]
            if len(m) >= 8:
                d.append(np.diff(r[m], 3))
        d = np.concatenate(d) if d else np.diff(r, 3)
        sigma = 1.4826 * float(np.median(np.abs(d))) / math.sqrt(20.0)
        out[name] = max(sigma, floor * data.full_scale)
    return out


# ----------------------------------------------------------------------------- models


class SweepModel:
    """Base circuit (``R1t, X, R2, R0, X0``; ``X1 = X2 = X``) plus one effect's extras."""

    def __init__(self, data: SweepData, effect: AdmittanceEffect | None, ctx: SweepContext, base_bounds):
        self.data = data
        self.base_bounds = base_bounds
        self.effect = effect
        self.ctx = ctx
        self.extra_names = tuple(effect.extra_names) if effect is not None else ()
        self.names = BASE_NAMES + self.extra_names
        self.k = len(self.extra_names)

    def circuit(self, x: np.ndarray) -> SweepCircuit:
        R1t, X, R2, R0, X0 = (float(v) for v in x[:5])
        c = SweepCircuit(R1t=R1t, X1=X, R2=R2, X2=X, R0=R0, X0=X0)
        if self.effect is not None:
            c = self.effect.augment(c, np.asarray(x[5:], float), self.ctx)
        return c

    def admittance(self, x: np.ndarray, mask=None) -> np.ndarray:
        d = self.data
        if mask is None:
            return self.circuit(x).admittance(d.s, d.V)
        c = self.circuit(x)
        if not np.isscalar(c.copper):
            c = c.with_(copper=np.asarray(c.copper)[mask])
        return c.admittance(d.s[mask], d.V[mask])

    def residual_complex(self, x, mask=None) -> np.ndarray:
        """(model - measured)/sigma per reading, complex (G + jB)."""
        Ym = self.data.Y if mask is None else self.data.Y[mask]
        with np.errstate(all="ignore"):
            return (self.admittance(x, mask) - Ym) / self.data.sigma

    def residuals(self, x, mask=None) -> np.ndarray:
        e = self.residual_complex(x, mask)
        r = np.concatenate([e.real, e.imag])
        return np.where(np.isfinite(r), r, 1e6)

    def ssr(self, x, mask=None) -> float:
        r = self.residuals(x, mask)
        return float(r @ r)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = self.base_bounds
        if self.effect is not None:
            elo, ehi = self.effect.extra_bounds(self.ctx)
            lo, hi = np.concatenate([lo, elo]), np.concatenate([hi, ehi])
        return lo, hi

    def fit(self, x0: np.ndarray, mask, max_nfev: int) -> np.ndarray:
        lo, hi = self.bounds()
        span = hi - lo
        u0 = np.clip((np.asarray(x0, float) - lo) / span, 1e-9, 1 - 1e-9)
        sol = least_squares(
            lambda u: self.residuals(lo + u * span, mask),
            u0,
            bounds=(0.0, 1.0),
            method="trf",
            x_scale="jac",
            max_nfev=max_nfev,
            xtol=1e-12,
            ftol=1e-12,
            gtol=1e-12,
        )
        return lo + sol.x * span


def _model_a(data: SweepData) -> tuple[complex, complex]:
    """Impedances read at standstill (series branches) and at synchronism (magnetising branch)."""
    near1 = np.abs(data.s - 1.0) <= np.min(np.abs(data.s - 1.0)) + 1e-9
    near0 = np.abs(data.s) <= np.min(np.abs(data.s)) + 1e-9
    return complex(np.mean(1.0 / data.Y[near1])), complex(np.mean(1.0 / data.Y[near0]))


def base_bounds(data: SweepData) -> tuple[np.ndarray, np.ndarray]:
    """Search ranges of ``R1t, X, R2, R0, X0`` from model A's crude reading, a decade either side."""
    Zsc, Znl = _model_a(data)
    R, X = abs(Zsc.real) / 2, abs(Zsc.imag) / 2
    X0 = max(abs(Znl.imag) - X, 2 * X)
    lo = np.array([R / 10, X / 10, R / 10, 0.0, X0 / 10])
    hi = np.array([10 * R, 10 * X, 10 * R, 10 * max(abs(Znl.real), R), 10 * X0])
    return lo, hi


def base_starts(data: SweepData, bounds) -> list[np.ndarray]:
    """Starts of the base fit: the bilinear regression (tie X1 = X2) and model A's crude reading."""
    lo, hi = bounds
    starts = []
    reg = bilinear_regression(data.s, data.Y, np.full(data.n, 1.0 / data.full_scale), model=6)
    for key in ("tied", "free"):
        t = reg[key]
        x = np.array([t["R1_total"], 0.5 * (t["X1"] + t["X2"]), t["R2"], t["R0"], t["X0"]], float)
        if np.all(np.isfinite(x)) and np.all(x >= lo) and np.all(x <= hi):
            starts.append(x)
    Zsc, Znl = _model_a(data)
    R, X = abs(Zsc.real) / 2, abs(Zsc.imag) / 2
    starts.append(np.clip([R, X, R, max(abs(Znl.real) - R, 0.0), max(abs(Znl.imag) - X, 2 * X)], lo, hi))
    return starts


def sweep_context(data: SweepData, x_base: np.ndarray) -> SweepContext:
    """Scales of the sweep from the data and the base circuit (no truth)."""
    Z1 = complex(x_base[0], x_base[1])
    E = np.abs(data.V - data.V * data.Y * Z1)
    I = np.abs(data.V * data.Y)
    top = data.level == len(data.levels) - 1
    stall = top & (np.abs(data.s - 1.0) == np.min(np.abs(data.s[top] - 1.0)))
    return SweepContext(
        E_top=float(np.max(E)),
        I_stall=float(np.mean(I[stall])),
        heat=heat_profile(data.time, data.V, data.Y),
    )


# ----------------------------------------------------------------------------- localisation


def localise(model: SweepModel, x: np.ndarray, s_near: float) -> dict:
    d = model.data
    e = model.residual_complex(x)
    eG, eB = e.real**2, e.imag**2
    energy = eG + eB
    total = float(energy.sum()) or 1.0
    regions = d.regions(s_near)
    by_region = {k: float(energy[m].sum() / total) for k, m in regions.items()}
    by_region_component = {
        f"{k}/{c}": float(v[m].sum() / total) for k, m in regions.items() for c, v in (("G", eG), ("B", eB))
    }
    by_level = {f"{v:.4g} V": float(energy[d.level == j].sum() / total) for j, v in enumerate(d.levels)}
    direction = _directions(d)
    by_direction = {k: float(energy[m].sum() / total) for k, m in direction.items() if m.any()}
    # mean signed residual (in noise units) per region and component: the signature's sign
    signs = {
        f"{k}/{c}": float(np.mean(v[m])) if m.any() else 0.0
        for k, m in regions.items()
        for c, v in (("G", e.real), ("B", e.imag))
    }
    return {
        "chi2_per_residual": float(energy.sum() / (2 * d.n)),
        "by_channel": {"G": float(eG.sum() / total), "B": float(eB.sum() / total)},
        "by_segment": by_region,
        "by_slip_region": by_region,
        "by_slip_region_and_component": by_region_component,
        "mean_residual_over_noise": signs,
        "by_voltage_level": by_level,
        "by_sweep_direction": by_direction,
        "current_residual_harmonics_A": {},
    }


def _directions(d: SweepData) -> dict[str, np.ndarray]:
    up = np.zeros(d.n, bool)
    down = np.zeros(d.n, bool)
    for k in np.unique(d.sweep):
        m = np.flatnonzero(d.sweep == k)
        if len(m) < 2:
            continue
        if d.s[m[-1]] < d.s[m[0]]:
            up[m] = True  # slip falling = speed rising
        else:
            down[m] = True
    return {"up": up, "down": down}


# ----------------------------------------------------------------------------- the diagnosis


def _best_fit(model: SweepModel, starts, mask, max_nfev: int):
    best, best_ssr = None, np.inf
    for x0 in starts:
        x = model.fit(x0, mask, max_nfev)
        v = model.ssr(x, mask)
        if v < best_ssr:
            best, best_ssr = x, v
    return best, best_ssr


def diagnose_sweep(
    ad: AdmittanceData,
    effects: dict[str, AdmittanceEffect],
    settings: AdmittanceDiagnosisSettings,
    progress=None,
) -> dict:
    """Steps 1-5 on one sweep data set; returns the diagnosis document (no truth)."""
    t0 = time.perf_counter()
    data = SweepData.from_data(ad)
    n_res = 2 * data.n
    # 1. base identification (in full-scale units until the noise is known)
    data.sigma = data.full_scale
    bounds = base_bounds(data)
    base = SweepModel(data, None, SweepContext(E_top=1.0, I_stall=1.0), bounds)
    x_base, _ = _best_fit(base, base_starts(data, bounds), None, 4 * settings.fit_evaluations)
    x_base = base.fit(x_base, None, 4 * settings.fit_evaluations)
    # 2. noise
    r_fs = base.residual_complex(x_base) * data.sigma
    sig = noise_estimate(data, r_fs, settings.noise_floor)
    if settings.noise is not None:
        sig = {"G": float(settings.noise), "B": float(settings.noise)}
    data.sigma = math.sqrt(0.5 * (sig["G"] ** 2 + sig["B"] ** 2))
    ctx = sweep_context(data, x_base)
    base = SweepModel(data, None, ctx, bounds)
    # 3. localisation
    loc = localise(base, x_base, settings.near_synchronism)
    fold_kind, folds = data.folds()
    base_fold = [base.fit(x_base, ~m, settings.fit_evaluations) for m in folds]
    held_base = sum(base.ssr(xf, m) for xf, m in zip(base_fold, folds, strict=True))
    held_vectors = {"none": np.concatenate([base.residuals(xf, m) for xf, m in zip(base_fold, folds, strict=True)])}
    ins_base = base.ssr(x_base)
    # 4. candidates
    ranking, fitted = [], {}
    for eff in effects.values():
        if progress:
            progress(eff.name)
        model = SweepModel(data, eff, ctx, bounds)
        starts = [np.concatenate([x_base, e]) for e in eff.extra_starts(ctx)]
        x_full, ssr_full = _best_fit(model, starts, None, settings.fit_evaluations)
        held_aug = 0.0
        xs = []
        for xf, m in zip(base_fold, folds, strict=True):
            st = [np.concatenate([xf, e]) for e in eff.extra_starts(ctx)] + [x_full]
            xk, _ = _best_fit(model, st, ~m, settings.fit_evaluations)
            xs.append(xk)
            held_aug += model.ssr(xk, m)
        held_vectors[eff.name] = np.concatenate([model.residuals(xk, m) for xk, m in zip(xs, folds, strict=True)])
        criterion = 0.5 * (ssr_full - ins_base) + model.k * math.log(n_res)
        ranking.append(
            {
                "effect": eff.name,
                "heldout_reduction": float(1.0 - held_aug / held_base) if held_base > 0 else 0.0,
                "in_sample_reduction": float(1.0 - ssr_full / ins_base) if ins_base > 0 else 0.0,
                "criterion": float(criterion),
                "heldout_chi2_before": float(held_base / n_res),
                "heldout_chi2_after": float(held_aug / n_res),
                "extra_parameters": {n: float(v) for n, v in zip(model.extra_names, x_full[5:], strict=True)},
                "extra_parameter_units": {n: eff.extra_unit(n) for n in model.extra_names},
            }
        )
        fitted[eff.name] = (model, x_full)
    ranking.sort(key=lambda r: -r["heldout_reduction"])
    # 5. verdict
    gap = held_base / n_res
    earned = [r for r in ranking if r["criterion"] < 0 and r["heldout_reduction"] >= settings.min_heldout_reduction]
    verdict = earned[0]["effect"] if (gap >= settings.min_gap and earned) else "none"
    held_after = gap if verdict == "none" else earned[0]["heldout_chi2_after"]
    doc = {
        "verdict": verdict,
        "ranking": ranking,
        "localisation": loc,
        "gap_before": {
            "heldout_chi2_per_residual": gap,
            "heldout_rms_over_noise": math.sqrt(gap),
            "in_sample_chi2_per_residual": ins_base / n_res,
            "rms_percent_of_full_scale": 100 * data.sigma / data.full_scale * math.sqrt(ins_base / n_res),
        },
        "gap_after": {
            "heldout_chi2_per_residual": held_after,
            "heldout_rms_over_noise": math.sqrt(held_after),
        },
        "heldout_scheme": {"kind": fold_kind, "folds": len(folds)},
        "base": {
            "model": "6-parameter circuit, X1 = X2",
            "estimate": {
                "R1_total": float(x_base[0]),
                "X1": float(x_base[1]),
                "R2": float(x_base[2]),
                "X2": float(x_base[1]),
                "R0": float(x_base[3]),
                "X0": float(x_base[4]),
            },
        },
        "noise_level": {
            "G_S": sig["G"],
            "B_S": sig["B"],
            "percent_of_full_scale": 100 * data.sigma / data.full_scale,
        },
        "scales": {
            "E_top_V": ctx.E_top,
            "I_stall_A": ctx.I_stall,
            "voltage_levels_V": data.levels.tolist(),
            "readings": data.n,
            "full_scale_admittance_S": data.full_scale,
        },
        "settings": asdict(settings),
        "wall_time_s": time.perf_counter() - t0,
    }
    doc.update(verdict_contract(settings, held_vectors, verdict, data.n))
    doc["_models"] = {"base": (base, x_base), "fitted": fitted}
    return doc


def verdict_contract(settings, held: dict, chosen: str, n_readings: int) -> dict:
    """The diagnosis contract shared with the time-domain side: ``status`` (``no_gap``,
    ``explained``, ``partly_explained``, ``unexplained``), ``verdict``, ``effects``,
    ``explained_share`` (of the excess held-out misfit above the noise) and the noise band of
    :func:`benchmark.core.uncertainty.misfit_ratio`. The noise of G and B comes from third
    differences of the base residual (a median: relative uncertainty about ``1.17 / sqrt(n)``).
    One effect at most is chosen on a sweep (no forward selection yet)."""
    from benchmark.core.noise_estimates import NoiseEstimate
    from benchmark.core.uncertainty import misfit_ratio

    u = 1.17 / math.sqrt(max(n_readings, 1))
    noise = NoiseEstimate(1.0, u, 2.0 * n_readings, "third differences of the base residual")
    before = misfit_ratio(held["none"], noise)
    after = misfit_ratio(held[chosen], noise) if chosen in held else before
    excess = before.ratio**2 - 1.0
    share = 0.0
    if excess > 0 and chosen != "none":
        share = float(np.clip((before.ratio**2 - after.ratio**2) / excess, 0.0, 1.0))
    near = after.ratio - 1.0 <= 2.0 * (after.threshold - 1.0)  # a gap many times the noise is not "explained"
    if before.ratio <= before.threshold:
        status, verdict, effects, share = "no_gap", "none", [], 0.0
    elif chosen != "none" and (after.ratio <= after.threshold or (share >= settings.explained_share and near)):
        status, verdict, effects = "explained", chosen, [chosen]
    elif chosen != "none" and share >= settings.partly_share:
        status, verdict, effects = "partly_explained", chosen, [chosen]
    else:
        status, verdict, effects = "unexplained", "unexplained", []
    return {"status": status, "verdict": verdict, "effects": effects, "explained_share": share,
            "per_effect": [{"effect": e, "drop_one_share": share, "parameters": {}} for e in effects],
            "indistinguishable": [], "excluded": [],
            "noise_band": [before.lower, before.threshold],
            "verdict_candidate": chosen}



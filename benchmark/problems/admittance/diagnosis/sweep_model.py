"""The slip sweep as the admittance diagnosis fits it (:class:`SweepData`, its noise estimate) and the
model of its readings, the base circuit and the base with effects (:class:`SweepModel`, the base's
bounds and starts)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import least_squares

from benchmark.problems.admittance.data import AdmittanceData
from benchmark.problems.admittance.effects import AdmittanceEffect
from benchmark.problems.admittance.problem import bilinear_regression
from benchmark.problems.admittance.sweep_circuit import SweepCircuit, SweepContext, heat_profile

#: The base circuit's parameters, in the order of a fit's vector.
BASE_NAMES = ("R1t", "X", "R2", "R0", "X0")


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
    sigma: float | np.ndarray = 1.0  # the noise's standard deviation on G and B, S: one or per reading

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


@dataclass(frozen=True)
class SweepNoise:
    """The readings' noise: standard deviation ``sigma_k = sqrt(level^2 ((1 - p) + p |Y_k|^2 / m))`` on G and on
    B of reading ``k`` (S), ``m`` the mean ``|Y|^2``: a constant part (an instrument's share of its range) and a
    part proportional to the reading (its share of the reading), ``p`` the proportional part's share."""

    per_reading: np.ndarray  # sigma_k, S
    G_S: float  # G's level at a reading of mean |Y|^2, S
    B_S: float
    proportional_share: float  # p, 0 = constant noise, 1 = a share of each reading
    constant_S: float  # sqrt(level^2 (1 - p)), S
    reading_fraction: float  # sqrt(level^2 p / m), standard deviation per unit |Y|
    allowed: tuple[np.ndarray, ...] = ()  # sigma_k of every shape the data do not tell apart from this one


def _third_differences(data: SweepData, residual: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Third differences of the residual (complex) within each sweep table in slip order, and the readings
    each one spans (four columns); a table of fewer than eight readings is left out unless all are."""
    d, idx = [], []
    for k in np.unique(data.sweep):
        m = np.flatnonzero(data.sweep == k)
        m = m[np.argsort(data.s[m], kind="stable")]
        if len(m) >= 8:
            d.append(np.diff(residual[m], 3))
            idx.append(np.stack([m[:-3], m[1:-2], m[2:-1], m[3:]], axis=1))
    if not d:
        m = np.arange(data.n)
        return np.diff(residual, 3), np.stack([m[:-3], m[1:-2], m[2:-1], m[3:]], axis=1)
    return np.concatenate(d), np.concatenate(idx)


#: Two log-likelihoods this far apart (twice the difference; chi^2 of one degree of freedom at 95 %) are
#: noise shapes the data tell apart.
SHAPE_INTERVAL = 3.84


def noise_estimate(data: SweepData, residual: np.ndarray, floor: float) -> SweepNoise:
    """The noise of G and B (S) from the base residual: within each sweep table, in slip order, third
    differences (a smooth model error is suppressed; white noise of standard deviations ``sigma_k`` has
    variance ``sigma_j^2 + 9 sigma_{j+1}^2 + 9 sigma_{j+2}^2 + sigma_{j+3}^2`` there).

    The shape across readings, the share ``p`` of :class:`SweepNoise`: the Gaussian likelihood of the
    differences (G's and B's together) is profiled over ``p`` (a log grid of the corner ``|Y|`` where the two
    parts are equal, and both pure forms), its maximum is the estimate; ``allowed`` holds the noise of every
    shape the data do not tell apart from it (:data:`SHAPE_INTERVAL`), for a gap to be claimed only where
    each of them leaves one. The level is robust: the median absolute difference over its standard
    deviation under the shape, for G and for B. With ``p = 0`` it is the median of
    ``|third difference| / sqrt(20)``, one level for all readings."""
    d, idx = _third_differences(data, residual)
    y2 = np.abs(data.Y) ** 2
    m = float(np.mean(y2)) or 1.0
    spanned = y2[idx] @ np.array([1.0, 9.0, 9.0, 1.0]) / m  # sum of c_i^2 |Y|^2 / m over each difference
    d2 = np.concatenate([d.real, d.imag]) ** 2
    lowest = floor * data.full_scale

    def profile(p: float) -> float:
        h = np.tile(np.maximum(20.0 * (1.0 - p) + p * spanned, 1e-300), 2)
        return float(np.sum(np.log(h)) + len(h) * np.log(np.mean(d2 / h)))

    def noise(p: float) -> SweepNoise:
        h = 20.0 * (1.0 - p) + p * spanned
        level = {  # (with p = 0 the scaling is exactly 1: the former single level to the last bit)
            name: max(1.4826 * float(np.median(np.abs(part) * np.sqrt(20.0 / h))) / math.sqrt(20.0), lowest)
            for name, part in (("G", d.real), ("B", d.imag))
        }
        pooled = math.sqrt(0.5 * (level["G"] ** 2 + level["B"] ** 2))
        return SweepNoise(
            per_reading=np.maximum(pooled * np.sqrt((1.0 - p) + p * y2 / m), lowest),
            G_S=level["G"],
            B_S=level["B"],
            proportional_share=p,
            constant_S=pooled * math.sqrt(1.0 - p),
            reading_fraction=pooled * math.sqrt(p / m),
        )

    y = np.sqrt(y2[y2 > 0]) if np.any(y2 > 0) else np.ones(1)
    corners = np.logspace(math.log10(y.min() / 10), math.log10(y.max() * 10), 121)
    shares = np.concatenate([[0.0], m / (corners[::-1] ** 2 + m), [1.0]])
    likelihood = np.array([profile(q) for q in shares])
    allowed = tuple(noise(float(q)).per_reading for q in shares[likelihood <= likelihood.min() + SHAPE_INTERVAL])
    return replace(noise(float(shares[int(np.argmin(likelihood))])), allowed=allowed)


def given_noise(data: SweepData, sigma: float) -> SweepNoise:
    """A noise level the user gives (``admittance_diagnosis.noise``): the same on every reading."""
    return SweepNoise(np.full(data.n, float(sigma)), float(sigma), float(sigma), 0.0, float(sigma), 0.0)


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
        sigma = self.data.sigma if mask is None or np.ndim(self.data.sigma) == 0 else self.data.sigma[mask]
        with np.errstate(all="ignore"):
            return (self.admittance(x, mask) - Ym) / sigma

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

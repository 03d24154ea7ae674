"""Joint time-domain fits of the base and augmented models used by the diagnosis.

The residual vector stacks, each divided by its channel's noise level (estimated from the
data, never from a truth file): the start-up currents ``i_alpha``, ``i_beta`` and speed, and
the free-motion part of the stop record (closed-form free motion from the measured speed at
its start). Parameters: ``Rs, Ls, Le, Rr, J, fv`` (+ ``fc`` with the case-2 base), then the
augmentation's extra parameters. All fits are local (trust-region least squares from the
base identification), in coordinates normalised to their bounds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from benchmark.core.effects import Effect, EffectContext
from benchmark.core.polish import least_squares_batch
from benchmark.problems.timedomain.data import StartupDataset
from benchmark.problems.timedomain.extended import base_rows, simulate_extended_batch, valid_rows
from benchmark.problems.timedomain.filters import free_motion_start, zero_phase_lowpass
from benchmark.problems.timedomain.mechanical import fit_free_stop
from benchmark.problems.timedomain.simulation import hold_is_linear

CHANNELS = ("i_alpha", "i_beta", "speed", "stop_speed")


def noise_level(x: np.ndarray, floor: float) -> float:
    """White-noise standard deviation of a sampled signal from its fourth differences (they
    suppress a smooth signal by (w Ts)^4 and are robust, through the median, to the few kinks
    of switched waveforms), at least the quantisation step / sqrt(12) when the values are
    quantised, and at least ``floor``."""
    x = np.asarray(x, float)
    d4 = np.diff(x, 4)
    sigma = 1.4826 * float(np.median(np.abs(d4 - np.median(d4)))) / np.sqrt(70.0)
    steps = np.abs(np.diff(x))
    steps = steps[steps > 0]
    if len(steps) > 10:
        q = float(np.min(steps))
        on_grid = np.abs(x / q - np.round(x / q)) < 1e-6
        if np.mean(on_grid) > 0.99:
            sigma = max(sigma, q / np.sqrt(12.0))
    return max(sigma, floor)


@dataclass
class DiagnosisData:
    """Measured channels of one data set, prepared for the diagnosis fits."""

    t: np.ndarray
    v_alpha: np.ndarray
    v_beta: np.ndarray
    meas: np.ndarray  # (3, N): i_alpha, i_beta, speed
    sample_time: float
    linear: bool
    pole_pairs: int
    stop_t: np.ndarray | None  # from the start of the free motion, s
    stop_speed: np.ndarray | None
    stop_w0: float | None
    sigma: dict  # channel -> noise level
    inertia: float | None
    dc_link_voltage: float | None

    @classmethod
    def from_dataset(cls, ds: StartupDataset) -> DiagnosisData:
        r = ds.startups[0]
        meas = np.stack([r.i_alpha, r.i_beta, r.speed])
        i_peak = float(np.max(np.abs(meas[:2])))
        sigma = {
            "i_alpha": noise_level(r.i_alpha, 1e-4 * i_peak),
            "i_beta": noise_level(r.i_beta, 1e-4 * i_peak),
            "speed": noise_level(r.speed, 1e-4 * float(np.max(np.abs(r.speed)))),
        }
        stop_t = stop_speed = w0 = None
        if ds.stops:
            st = ds.stops[0]
            dt = float(np.median(np.diff(st.t)))
            k0 = free_motion_start(st.t, zero_phase_lowpass(st.speed, dt))
            ws = zero_phase_lowpass(st.speed, dt)
            moving = np.flatnonzero(ws[k0:] > 0.02 * ws[k0]) + k0
            k1 = moving[-1] + 1 if len(moving) else len(ws)
            stop_t = st.t[k0:k1] - st.t[k0]
            stop_speed = st.speed[k0:k1]
            w0 = float(ws[k0])
            sigma["stop_speed"] = noise_level(st.speed[k0:k1], 1e-4 * max(w0, 1e-9))
        return cls(t=r.t, v_alpha=np.ascontiguousarray(r.v_alpha), v_beta=np.ascontiguousarray(r.v_beta),
                   meas=meas, sample_time=ds.sample_time, linear=hold_is_linear(ds.input_hold),
                   pole_pairs=ds.pole_pairs, stop_t=stop_t, stop_speed=stop_speed, stop_w0=w0, sigma=sigma,
                   inertia=ds.inertia, dc_link_voltage=ds.dc_link_voltage)

    @property
    def n_startup(self) -> int:
        return len(self.t)

    def channel_slices(self) -> dict[str, slice]:
        n = self.n_startup
        out = {"i_alpha": slice(0, n), "i_beta": slice(n, 2 * n), "speed": slice(2 * n, 3 * n)}
        if self.stop_t is not None:
            out["stop_speed"] = slice(3 * n, 3 * n + len(self.stop_t))
        return out

    @property
    def n_residuals(self) -> int:
        return 3 * self.n_startup + (0 if self.stop_t is None else len(self.stop_t))

    def time_of_residuals(self) -> np.ndarray:
        """Time of each residual element (start-up channels: their sample time; stop: the
        start-up's end plus the time into the free motion)."""
        parts = [self.t, self.t, self.t]
        if self.stop_t is not None:
            parts.append(self.t[-1] + self.stop_t)
        return np.concatenate(parts)

    def folds(self, supply_frequency: float) -> tuple[np.ndarray, np.ndarray]:
        """Two interleaved folds of blocks (two supply periods of the start-up, one second of
        the stop): each fold is a held-out set for a fit on the other."""
        block = 2.0 / supply_frequency
        kA = (np.floor(self.t / block).astype(int) % 2) == 0
        parts = [kA, kA, kA]
        if self.stop_t is not None:
            parts.append((np.floor(self.stop_t / 1.0).astype(int) % 2) == 0)
        a = np.concatenate(parts)
        return a, ~a


class JointModel:
    """Base (+ one effect) model with the joint residual of :class:`DiagnosisData`."""

    def __init__(self, data: DiagnosisData, base_case: int, effect: Effect | None, ctx: EffectContext,
                 centre: dict[str, float]):
        self.data = data
        self.effect = effect
        self.ctx = ctx
        self.base_case = base_case
        names = ["Rs", "Ls", "Le", "Rr"] + (["J"] if data.inertia is None else []) + ["fv"]
        if base_case == 2:
            names.append("fc")
        self.base_names = tuple(names)
        extra = tuple(effect.extra_names) if effect else ()
        self.names = self.base_names + extra
        c = np.array([centre[n] for n in self.base_names])
        lo = 0.5 * c
        hi = 2.0 * c
        for k, n in enumerate(self.base_names):
            if n in ("fv", "fc"):
                lo[k], hi[k] = 0.1 * c[k], 5.0 * c[k] + 1e-9
        if effect:
            elo, ehi = effect.extra_bounds(ctx)
            lo, hi = np.concatenate([lo, elo]), np.concatenate([hi, ehi])
        self.lower, self.upper = lo, hi
        sig = data.sigma
        w = [np.full(data.n_startup, 1.0 / sig[k]) for k in ("i_alpha", "i_beta", "speed")]
        if data.stop_t is not None:
            w.append(np.full(len(data.stop_t), 1.0 / sig["stop_speed"]))
        self.weight = np.concatenate(w)
        meas = [data.meas[0], data.meas[1], data.meas[2]]
        if data.stop_t is not None:
            meas.append(data.stop_speed)
        self.measured = np.concatenate(meas)

    def full_parameters(self, X: np.ndarray) -> np.ndarray:
        col = {n: X[:, k] for k, n in enumerate(self.names)}
        J = col["J"] if "J" in col else np.full(len(X), self.data.inertia)
        fc = col["fc"] if "fc" in col else np.zeros(len(X))
        return np.column_stack([col["Rs"], col["Ls"], col["Le"], col["Rr"], J, col["fv"], fc])

    def rows(self, X: np.ndarray) -> np.ndarray:
        X = np.atleast_2d(X)
        rows = base_rows(self.full_parameters(X), self.data.pole_pairs)
        if self.effect is not None:
            rows = self.effect.augment(rows, X[:, len(self.base_names):], self.ctx)
        rows[~valid_rows(rows)] = np.nan
        return np.ascontiguousarray(rows)

    def simulate(self, X: np.ndarray) -> np.ndarray:
        """Model outputs in the residual layout, (n, n_residuals)."""
        X = np.atleast_2d(X)
        rows = self.rows(X)
        d = self.data
        sim = simulate_extended_batch(rows, d.v_alpha, d.v_beta, d.linear, d.sample_time, 1)
        parts = [sim.reshape(len(X), -1)]
        if d.stop_t is not None:
            theta = self.full_parameters(X)
            J, fv, fc = theta[:, 4:5], theta[:, 5:6], theta[:, 6:7]
            rows_fc = rows[:, [19]]  # an effect may set fc (Coulomb augmentation)
            fc = np.where(np.isfinite(rows_fc), rows_fc, fc)
            with np.errstate(all="ignore"):
                tau = J / fv
                c = fc / J
                free = (d.stop_w0 + tau * c) * np.exp(-d.stop_t[None, :] / tau) - tau * c
            parts.append(np.maximum(free, 0.0))
        return np.concatenate(parts, axis=1)

    def residuals(self, X: np.ndarray) -> np.ndarray:
        r = (self.measured[None, :] - self.simulate(X)) * self.weight[None, :]
        return np.where(np.isfinite(r), r, 1e6)

    def fit(self, x0: np.ndarray, mask: np.ndarray | None, max_evaluations: int = 400) -> np.ndarray:
        sel = slice(None) if mask is None else mask

        def res(X):
            return self.residuals(X)[:, sel]

        x, _ = least_squares_batch(res, np.clip(x0, self.lower, self.upper), self.lower, self.upper,
                                   max_evaluations, rel_step=1e-6)
        return x

    def ssr(self, x: np.ndarray, mask: np.ndarray | None = None) -> float:
        r = self.residuals(np.atleast_2d(x))[0]
        return float(np.sum(r[mask] ** 2) if mask is not None else np.sum(r**2))


def stop_mechanics(data: DiagnosisData, case: int):
    """The mechanical pre-identification on the free-motion record (for starting values)."""
    if data.stop_t is None:
        return None
    return fit_free_stop(data.stop_t, data.stop_speed, case=case, filter_speed=True)

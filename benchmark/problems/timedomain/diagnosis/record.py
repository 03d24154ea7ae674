"""The record as the diagnosis's fits see it (:class:`DiagnosisData`): the measured start-up
channels and the free stop's part that the model follows, each channel's noise level, the model's
kept outputs and coasts, and how the fits on it ended (:class:`FitTally`)."""

from __future__ import annotations

import threading
from dataclasses import dataclass, field

import numpy as np

from benchmark.problems.timedomain.data import StartupDataset
from benchmark.problems.timedomain.diagnosis.folds import segment_folds
from benchmark.problems.timedomain.diagnosis.kernel_cache import CACHE_ROWS, KernelCache, RowCache
from benchmark.problems.timedomain.filters import free_motion_start, zero_phase_lowpass
from benchmark.problems.timedomain.noise import record_noise, stop_noise
from benchmark.problems.timedomain.simulation import hold_is_linear
from benchmark.problems.timedomain.speed_filter import filter_pole


class FitTally:
    """How the local fits of one record ended, per evaluation cap: ``{cap: [fits, stopped at
    the cap]}`` (a fit stopped at its cap did not converge; safe to use from several threads).
    The diagnosis reports the fits run to convergence (``diagnosis.max_iterations``) that did
    not: a verdict may hang on where they stopped."""

    def __init__(self):
        self.by_cap: dict[int, list[int]] = {}
        self._lock = threading.Lock()

    def record(self, cap: int, at_cap: bool) -> None:
        with self._lock:
            row = self.by_cap.setdefault(int(cap), [0, 0])
            row[0] += 1
            row[1] += bool(at_cap)


#: Bytes the stop's kept coasts may take (``DiagnosisData.coasts``): :data:`CACHE_ROWS` coasts of a
#: stop up to 130000 samples (a 26 s stop at 5 kHz), fewer (at least 8) of a longer one.
COAST_STORE_BYTES = 50_000_000


@dataclass
class DiagnosisData:
    """Measured channels of one data set, prepared for the diagnosis fits."""

    t: np.ndarray
    v_alpha: np.ndarray
    v_beta: np.ndarray
    meas: np.ndarray  # (3, N): i_alpha, i_beta, speed (speed NaN when not measured)
    sample_time: float
    linear: bool
    pole_pairs: int
    stop_t: np.ndarray | None  # from the start of the free motion, s
    stop_speed: np.ndarray | None
    stop_w0: float | None
    noise: dict  # channel -> NoiseEstimate
    inertia: float | None
    dc_link_voltage: float | None
    input_hold: str
    supply_frequency: float
    current_used: np.ndarray | None = None  # (N,) False where the conditioning masked a current sample
    kernel: KernelCache = field(init=False, repr=False, compare=False)  # the model's outputs of this input
    coasts: RowCache = field(init=False, repr=False, compare=False)  # the stop's coasts (JointModel.recorded_stop)
    fits: FitTally = field(init=False, repr=False, compare=False)  # how the fits on this record ended

    def __post_init__(self):
        self.kernel = KernelCache(self.v_alpha, self.v_beta, self.linear, self.sample_time)
        n_stop = 0 if self.stop_t is None else len(self.stop_t)
        self.coasts = RowCache(int(np.clip(COAST_STORE_BYTES // max(8 * n_stop, 1), 8, CACHE_ROWS)))
        self.fits = FitTally()

    @classmethod
    def from_dataset(cls, ds: StartupDataset) -> DiagnosisData:
        r = ds.startups[0]
        speed = np.asarray(r.speed, float)
        meas = np.stack([r.i_alpha, r.i_beta, speed])
        noise, f_supply = record_noise(r, ds.supply_frequency, ds.speed_filter)
        stop_t = stop_speed = w0 = None
        if ds.stops:
            st = ds.stops[0]
            dt = float(np.median(np.diff(st.t)))
            ws = zero_phase_lowpass(st.speed, dt)
            k0 = free_motion_start(st.t, ws)
            moving = np.flatnonzero(ws[k0:] > 0.02 * ws[k0]) + k0
            k1 = moving[-1] + 1 if len(moving) else len(ws)
            stop_t = st.t[k0:k1] - st.t[k0]
            stop_speed = st.speed[k0:k1]
            w0 = float(ws[k0])
            noise["stop_speed"] = stop_noise(stop_speed, w0, filter_pole(ds.speed_filter, dt))
        return cls(t=r.t, v_alpha=np.ascontiguousarray(r.v_alpha), v_beta=np.ascontiguousarray(r.v_beta),
                   meas=meas, sample_time=ds.sample_time, linear=hold_is_linear(ds.input_hold),
                   pole_pairs=ds.pole_pairs, stop_t=stop_t, stop_speed=stop_speed, stop_w0=w0, noise=noise,
                   inertia=ds.inertia, dc_link_voltage=ds.dc_link_voltage, input_hold=str(ds.input_hold),
                   supply_frequency=float(f_supply),
                   current_used=None if r.weight is None else np.asarray(r.weight, bool).copy())

    @property
    def has_speed(self) -> bool:
        return "speed" in self.noise

    @property
    def sigma(self) -> dict[str, float]:
        return {k: float(v.std) for k, v in self.noise.items()}

    @property
    def n_startup(self) -> int:
        return len(self.t)

    def startup_channels(self) -> list[int]:
        """Rows of the simulated (3, N) output that are measured."""
        return [0, 1, 2] if self.has_speed else [0, 1]

    def channel_slices(self) -> dict[str, slice]:
        n = self.n_startup
        out = {}
        for k, ch in enumerate(c for c in ("i_alpha", "i_beta", "speed") if c in self.noise):
            out[ch] = slice(k * n, (k + 1) * n)
        if self.stop_t is not None:
            m = len(out) * n
            out["stop_speed"] = slice(m, m + len(self.stop_t))
        return out

    @property
    def n_residuals(self) -> int:
        return len(self.startup_channels()) * self.n_startup + (0 if self.stop_t is None else len(self.stop_t))

    def channel_labels(self) -> np.ndarray:
        lab = np.empty(self.n_residuals, dtype=int)
        for k, s in enumerate(self.channel_slices().values()):
            lab[s] = k
        return lab

    def time_of_residuals(self) -> np.ndarray:
        """Time of each residual element (start-up channels: their sample time; stop: the
        start-up's end plus the time into the free motion)."""
        parts = [self.t] * len(self.startup_channels())
        if self.stop_t is not None:
            parts.append(self.t[-1] + self.stop_t)
        return np.concatenate(parts)

    def used(self) -> np.ndarray:
        """(n_residuals,) False at the current samples the conditioning masked (clipped or
        flattened by a saturating probe, the switching window): they weigh nothing in any fit
        and belong to no fold."""
        parts = []
        for c in self.startup_channels():
            if c < 2 and self.current_used is not None:
                parts.append(self.current_used)
            else:
                parts.append(np.ones(self.n_startup, bool))
        if self.stop_t is not None:
            parts.append(np.ones(len(self.stop_t), bool))
        return np.concatenate(parts)

    def folds(self) -> tuple[np.ndarray, np.ndarray]:
        """The diagnosis's two held-out folds, cut by segment of the experiment
        (:func:`.folds.segment_folds`)."""
        return segment_folds(self)

    def facts(self, base_case: int) -> dict:
        """What the experiment says about itself: which effects can occur in it."""
        return {"input_hold": self.input_hold, "dc_link_voltage": self.dc_link_voltage,
                "supply_frequency": self.supply_frequency, "has_speed": self.has_speed,
                "has_stop": self.stop_t is not None, "base_case": int(base_case)}

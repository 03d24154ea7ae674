"""Joint time-domain fits of the base model and the base plus a set of effects.

The residual vector stacks, each divided by its channel's noise level (estimated from the
data, never from a truth file, :mod:`.noise`): the start-up currents ``i_alpha``, ``i_beta``,
the speed (left out when the record has no speed sensor: an all-NaN channel) and the
free-motion part of the stop record (closed-form free motion from the measured speed at its
start). Parameters: ``Rs, Ls, Le, Rr, J, fv, fc`` (``J`` when not known; ``fc`` with the
case-2 base), then each chosen effect's extra parameters in order. The model applies every
effect's ``augment`` to the extended-model rows in turn, runs the kernel, then every effect's
``measure`` (an output transform of the simulated ``(n, 3, N)`` [i_alpha, i_beta, speed]) in
turn. All fits are local (trust-region least squares with a forward-difference Jacobian
batched through the kernel), in coordinates normalised to their bounds.
"""

from __future__ import annotations

from dataclasses import fields

import numpy as np

from benchmark.core.capped_least_squares import capped_least_squares
from benchmark.core.effects import Effect, EffectContext
from benchmark.core.noise_estimates import NoiseEstimate
from benchmark.core.uncertainty import hac_covariance_floored, standard_errors
from benchmark.problems.timedomain.diagnosis.engine import quiet
from benchmark.problems.timedomain.diagnosis.free_coast import FreeCoast, switched_at_end
from benchmark.problems.timedomain.diagnosis.record import DiagnosisData
from benchmark.problems.timedomain.extended import IDX, base_rows, valid_rows
from benchmark.problems.timedomain.mechanical import fit_free_stop
from benchmark.problems.timedomain.speed_filter import (
    first_order_lag,
    speed_read_through,
    stated_speed_filter,
)

CHANNELS = ("i_alpha", "i_beta", "speed", "stop_speed")
DIVERGED = 1e6


class JointModel:
    """Base model (+ a list of effects) with the joint residual of :class:`DiagnosisData`.

    The local fits search the base parameters in a box about ``centre`` (``[c / span, c span]``;
    ``fv`` in ``[0.1 fv, 5 fv + fc_scale / w_sync]``, ``fc`` in ``[0, 5 fc + fc_scale]``, with
    ``fc_scale`` a torque, N m) and each effect's extras in its own bounds."""

    def __init__(self, data: DiagnosisData, base_case: int, effects: list[Effect] | tuple, ctx: EffectContext,
                 centre: dict[str, float], fc_scale: float, span: float = 2.0):
        self.data = data
        self.effects = list(effects)
        self.ctx = ctx
        self.base_case = base_case
        names = ["Rs", "Ls", "Le", "Rr"] + (["J"] if data.inertia is None else []) + ["fv"]
        if base_case == 2:
            names.append("fc")
        self.base_names = tuple(names)
        self.slices = []
        k = len(self.base_names)
        extra = []
        for eff in self.effects:
            m = len(eff.extra_names)
            self.slices.append(slice(k, k + m))
            extra += [f"{eff.name}.{n}" for n in eff.extra_names]
            k += m
        self.names = self.base_names + tuple(extra)
        c = np.array([centre[n] for n in self.base_names])
        lo, hi = c / span, c * span  # the box the local fits search around the base estimate
        for j, n in enumerate(self.base_names):
            if n == "fv":
                lo[j], hi[j] = 0.1 * c[j], 5.0 * c[j] + fc_scale / max(ctx.w_sync, 1e-9)
            if n == "fc":
                lo[j], hi[j] = 0.0, 5.0 * c[j] + fc_scale
        for eff in self.effects:
            elo, ehi = eff.fit_bounds(ctx)
            lo, hi = np.concatenate([lo, elo]), np.concatenate([hi, ehi])
        self.lower, self.upper = lo, hi
        sl = data.channel_slices()
        w = np.empty(data.n_residuals)
        for ch, s in sl.items():
            w[s] = 1.0 / data.noise[ch].std
        self.weight = np.where(data.used(), w, 0.0)  # masked samples: residual 0
        meas = [data.meas[k] for k in data.startup_channels()]
        if data.stop_t is not None:
            meas.append(data.stop_speed)
        self.measured = np.concatenate(meas)
        self._rows_out = data.startup_channels()
        pairs = list(zip(self.effects, self.slices, strict=True))
        self._measure_order = sorted(pairs, key=lambda p: getattr(p[0], "measure_stage", 0))
        #: The speed channel's filter (s) meta.yaml states, read by every model (0: none).
        self.speed_filter = stated_speed_filter(ctx.facts)

    @property
    def effect_names(self) -> list[str]:
        return [e.name for e in self.effects]

    def full_parameters(self, X: np.ndarray) -> np.ndarray:
        col = {n: X[:, k] for k, n in enumerate(self.base_names)}
        J = col["J"] if "J" in col else np.full(len(X), self.data.inertia)
        fc = col["fc"] if "fc" in col else np.zeros(len(X))
        return np.column_stack([col["Rs"], col["Ls"], col["Le"], col["Rr"], J, col["fv"], fc])

    def rows(self, X: np.ndarray) -> np.ndarray:
        X = np.atleast_2d(X)
        rows = base_rows(self.full_parameters(X), self.data.pole_pairs)
        for eff, s in zip(self.effects, self.slices, strict=True):
            rows = eff.augment(rows, X[:, s], self.ctx)
        rows = np.array(rows, dtype=float)
        rows[~valid_rows(rows)] = np.nan
        return np.ascontiguousarray(rows)

    def simulate(self, X: np.ndarray) -> np.ndarray:
        """Model outputs in the residual layout, (n, n_residuals)."""
        X = np.atleast_2d(X)
        rows = self.rows(X)
        return self.outputs(X, rows, self.data.kernel.simulate(rows))

    def outputs(self, X: np.ndarray, rows: np.ndarray, sim: np.ndarray) -> np.ndarray:
        """Model outputs in the residual layout (n, n_residuals) from the extended model's
        outputs ``sim`` (n, 3, N) of ``rows = self.rows(X)``: the sensors' transforms, the
        instrument's speed filter, the stop."""
        d = self.data
        for eff, s in self._measure_order:
            measure = getattr(eff, "measure", None)
            if measure is not None:
                sim = measure(sim, X[:, s], self.ctx)
        sim = speed_read_through(sim, self.speed_filter, self.ctx.sample_time or 1.0)
        out = np.empty((len(X), d.n_residuals))
        k = len(self._rows_out) * d.n_startup
        out[:, :k] = np.asarray(sim)[:, self._rows_out, :].reshape(len(X), -1)
        if d.stop_t is not None:
            out[:, k:] = self.recorded_stop(X, rows)
        return out

    def recorded_stop(self, X: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """The stop record as the speed sensor gives it (n, N_stop), with the speed at the stop's
        start profiled out: the filtered measured speed there is off by a few tenths of a rad/s
        where the trapped flux still brakes the rotor in the first tenth of a second, or where a
        tachometer's ripple or gain sits on it, and a fixed start biases the whole coast (a
        load torque was then chosen to bend it back). ``w0`` is fitted to the record with the
        sensors' deterministic part undone (:meth:`Effect.stop_true_speed`) in one Gauss-Newton
        step (the coast is nearly linear in it), limited to 5 % of the measured start."""
        d = self.data
        inputs = self.coast_inputs(X, rows)
        undo = [(eff, s) for eff, s in reversed(self._measure_order)
                if type(eff).stop_true_speed is not Effect.stop_true_speed]
        # what a row's coast is computed from: its mechanics, and the sensors undone on the record
        head = (tuple(eff.name for eff, _ in undo), self._context_key()) if undo else ()
        cols = np.ascontiguousarray(np.hstack([*inputs, *(X[:, s] for _, s in undo)]), dtype=float)
        stop = d.coasts.get([(head, self.speed_filter, r.tobytes()) for r in cols],  # profiled through the filter
                            lambda first: self._profiled_coast(X[first], [a[first] for a in inputs], undo),
                            (len(d.stop_t),))
        for eff, s in self._measure_order:  # the same speed sensor records the stop
            stop = eff.measure_stop(stop, X[:, s], self.ctx, d.stop_t, d.stop_speed)
        return self._stop_filter(stop)  # ... through the same filter

    def _stop_filter(self, w: np.ndarray) -> np.ndarray:
        """Rows of a stop's speed (n, N_stop) through the stated speed filter (unchanged without one)."""
        t = self.data.stop_t
        if self.speed_filter > 0.0 and len(t) > 1:
            return first_order_lag(w, self.speed_filter, float(np.median(np.diff(t))))
        return w

    def _context_key(self) -> tuple:
        """The context's fields as a key (a sensor's :meth:`Effect.stop_true_speed` reads them)."""
        ctx = self.ctx
        return tuple(getattr(ctx, f.name) for f in fields(ctx) if f.name != "facts") + (repr(ctx.facts),)

    def _profiled_coast(self, X: np.ndarray, inputs: list[np.ndarray], undo: list) -> np.ndarray:
        """The true speed of the stop (n, N_stop) of rows whose coast is computed from ``inputs``
        (:meth:`coast_inputs`), the speed at its start profiled (:meth:`recorded_stop`) on the
        record with the sensors ``undo`` undone, the coast read through the stated filter (a
        coast that decelerates is read ``tau dw/dt`` above its speed: a start fitted without it
        took that lag, and the filter then added it again, 0.3 noise standard deviations over
        a 22 s motulator coast, an effect-free record called ``unexplained``); each row's speed
        depends on its own inputs only."""
        d = self.data
        y = np.broadcast_to(d.stop_speed[None, :], (len(X), len(d.stop_t)))
        w0 = np.full((len(X), 1), float(d.stop_w0))
        for eff, s in undo:  # the recorded stop, sensors undone
            y = eff.stop_true_speed(y, X[:, s], self.ctx)
            w0 = eff.stop_true_speed(w0, X[:, s], self.ctx)
        h = 1e-3 * max(abs(float(d.stop_w0)), 1.0)
        coast = FreeCoast(d.stop_t, *inputs)
        with np.errstate(all="ignore"):
            base = coast.speed(w0)
            D = (self._stop_filter(coast.speed(w0 + h)) - self._stop_filter(base)) / h
            base = self._stop_filter(base)
            step = (np.nansum((y - base) * D, axis=1, keepdims=True)
                    / np.maximum(np.nansum(D * D, axis=1, keepdims=True), 1e-300))
        limit = 0.05 * abs(float(d.stop_w0))
        return coast.speed(w0 + np.clip(np.nan_to_num(step), -limit, limit))

    def free_stop(self, X: np.ndarray, rows: np.ndarray, w0: np.ndarray | None = None) -> np.ndarray:
        """Speed of the free stop from the speed at its start (``w0`` (n, 1), rad/s; the measured
        one when None): the closed form of :mod:`.free_coast` for the rows' mechanics
        (:meth:`coast`)."""
        d = self.data
        w0 = d.stop_w0 if w0 is None else w0
        return self.coast(X, rows).speed(np.broadcast_to(np.asarray(w0, float), (len(X), 1)))

    def coast(self, X: np.ndarray, rows: np.ndarray) -> FreeCoast:
        """The free coast of the rows (:meth:`coast_inputs`)."""
        return FreeCoast(self.data.stop_t, *self.coast_inputs(X, rows))

    def coast_inputs(self, X: np.ndarray, rows: np.ndarray) -> list[np.ndarray]:
        """What the free coast of the rows is computed from, :class:`.free_coast.FreeCoast`'s
        arguments after the times, each an (n, 1) column: ``J dw/dt = -(A + B w + C w^2)`` with
        ``A`` Coulomb friction plus the passive load torques (constant, and the switched load's
        constant part as it stands at the start-up's end, :func:`switched_at_end`), ``B = fv``
        plus the switched load's part that follows speed (``B_a``: a DC generator still on its
        resistor, through its armature's lag ``tau_s``; an eddy-current brake's law when
        ``r_crit`` > 0, integrated), ``C`` a fan load over ``w_ref^2``."""
        d = self.data
        theta = self.full_parameters(X)
        J, fv = theta[:, 4:5], theta[:, 5:6]
        col = {k: rows[:, [IDX[k]]] if k in IDX else np.zeros((len(X), 1))
               for k in ("fc", "T_L", "T_q", "w_ref", "T_s", "t_step", "T_s_speed", "tau_s", "t_step_off", "r_crit")}
        fc = np.where(np.isfinite(col["fc"]), col["fc"], theta[:, 6:7])  # an effect may set fc
        step_on = switched_at_end(col, float(d.t[-1]))
        A = fc + col["T_L"] + col["T_s"] * step_on * (1.0 - col["T_s_speed"])
        B_a = col["T_s"] * step_on * col["T_s_speed"] / col["w_ref"]  # a switched load that follows speed
        fv = fv + B_a
        with np.errstate(all="ignore"):
            C = np.where(col["w_ref"] > 0, col["T_q"] / np.maximum(col["w_ref"], 1e-12) ** 2, 0.0)
        return [J, fv, A, C, B_a, col["tau_s"],  # its armature's lag (tau_s > 0)
                col["r_crit"], col["w_ref"]]  # an eddy-current brake's law (r_crit > 0)

    def residuals(self, X: np.ndarray) -> np.ndarray:
        return self.residuals_of(self.simulate(X), overwrite=True)

    def residuals_of(self, outputs: np.ndarray, overwrite: bool = False) -> np.ndarray:
        """Noise-normalised residuals (n, n_residuals) of model outputs (:meth:`simulate`), a
        diverged output :data:`DIVERGED`; ``overwrite``: in the array ``outputs``."""
        r = outputs if overwrite else np.array(outputs, dtype=float)
        with np.errstate(all="ignore"):
            np.subtract(self.measured[None, :], r, out=r)
            r *= self.weight[None, :]
        bad = ~np.isfinite(r)
        if bad.any():
            r[bad] = DIVERGED
        return r

    def fit(self, x0: np.ndarray, mask: np.ndarray | None, max_iterations: int = 12,
            tol: float = 1e-5, held: dict[int, float] | None = None) -> np.ndarray:
        """Local least squares from ``x0`` of :meth:`objective`: the residuals in ``mask`` (all when
        None) and the effects' priors. ``held`` maps parameter indices to values held fixed; a
        parameter whose bounds coincide is held at them too. Held parameters take no part in the
        fit (no Jacobian column, no simulation)."""
        lo, hi = self.lower.copy(), self.upper.copy()
        for k, value in (held or {}).items():
            lo[k] = hi[k] = value
        free = np.flatnonzero(hi > lo)
        x_held = np.clip(np.asarray(x0, float), lo, hi)
        lo_f, width = lo[free], hi[free] - lo[free]
        cache: dict = {}

        def to_x(U):
            X = np.repeat(x_held[None, :], len(U), axis=0)
            X[:, free] = lo_f + np.clip(U, 0.0, 1.0) * width
            return X

        def fun(u):
            r = self.objective(to_x(u[None, :]), mask)[0]
            cache["u"], cache["r"] = u.copy(), r
            return r

        def jac(u):
            r0 = cache["r"] if "u" in cache and np.array_equal(cache["u"], u) else fun(u)
            h = 1e-6 * np.maximum(np.abs(u), 1e-3)
            h = np.where(u + h > 1.0, -h, h)
            R = self.objective(to_x(u[None, :] + np.diag(h)), mask)
            return ((R - r0[None, :]) / h[:, None]).T

        if not len(free):
            return x_held
        u0 = (x_held[free] - lo_f) / width
        with quiet():
            sol, at_cap = capped_least_squares(fun, jac, u0, max_iterations, bounds=(0.0, 1.0), x_scale="jac",
                                               xtol=tol, ftol=tol, gtol=1e-8)
        self.data.fits.record(max_iterations, at_cap)
        return to_x(sol.x[None, :])[0]

    def prior(self, X: np.ndarray) -> np.ndarray:
        """The effects' prior residuals (n, m) toward their absence (:meth:`Effect.prior_residuals`),
        part of what every fit minimises, not of any held-out score."""
        X = np.atleast_2d(X)
        return np.concatenate([np.zeros((len(X), 0))] + [eff.prior_residuals(X[:, s], self.ctx)
                                                        for eff, s in zip(self.effects, self.slices, strict=True)],
                              axis=1)

    def objective(self, X: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
        """What :meth:`fit` makes small, per row of ``X`` (n, m): the residuals on ``mask`` (all
        when None) followed by the effects' priors (:meth:`prior`)."""
        X = np.atleast_2d(X)
        return np.concatenate([self.residuals(X)[:, slice(None) if mask is None else mask], self.prior(X)], axis=1)

    def ssr(self, x: np.ndarray, mask: np.ndarray | None = None) -> float:
        """What :meth:`fit` minimises at ``x``: the squared residuals on ``mask`` (all when None)
        and the effects' priors."""
        x = np.atleast_2d(x)
        r = self.residuals(x)[0]
        return float((np.sum(r[mask] ** 2) if mask is not None else np.sum(r**2)) + np.sum(self.prior(x) ** 2))

    def standard_errors(self, x: np.ndarray) -> np.ndarray:
        """Standard errors of ``x`` (a fit on all residuals) from the coloured-residual
        (HAC) sandwich covariance, by the identification's rule (the Andrews bandwidth, at least
        one supply period: :func:`benchmark.core.uncertainty.hac_covariance_floored`)."""
        x = np.asarray(x, float)
        h = 1e-6 * np.maximum(np.abs(x), 1e-9 + 1e-6 * (self.upper - self.lower))
        X = x[None, :] + np.diag(h)
        r0 = self.residuals(x[None, :])[0]
        R = self.residuals(X)
        J = -((R - r0[None, :]) / h[:, None]).T  # d(model/sigma)/dx (sign does not matter)
        with quiet():
            try:
                floor = 1.0 / (self.data.supply_frequency * self.data.sample_time)
                cov, _ = hac_covariance_floored(J, r0, groups=self.data.channel_labels(), floor=floor, aligned=False)
            except (ValueError, np.linalg.LinAlgError):
                return np.full(len(x), np.nan)
        # a parameter the residuals do not depend on here (the magnetising node's place while
        # the leakage saturates too) is not determined: nan, not the pseudo-inverse's 0
        return np.where(np.any(J != 0.0, axis=0), standard_errors(cov), np.nan)


def stop_mechanics(data: DiagnosisData, case: int):
    """The mechanical pre-identification on the free-motion record (for starting values)."""
    if data.stop_t is None:
        return None
    return fit_free_stop(data.stop_t, data.stop_speed, case=case, filter_speed=True)


def unit_noise(u: float, n_eff: float) -> NoiseEstimate:
    return NoiseEstimate(1.0, float(u), float(n_eff), "channels normalised by their own noise")

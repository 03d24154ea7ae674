"""The switch-on flux step: a nuisance of the time-domain problem (:mod:`benchmark.core.nuisance`).

A measured switch-on's contactor poles close and bounce between samples; the conditioning
corrects their volt-seconds from the current's response
(:func:`benchmark.problems.timedomain.switch_on.switching_steps`) and records where its steps end
(``StartupRecord.switch_on_sample``). What is left of their error is a stator flux step there:
two nuisance parameters (alpha, beta, V s) estimated with the motor's parameters. The mixin
expects the problem's ``dataset`` and ``_records`` (tuples starting with the alpha and beta
voltages) and its ``residuals_batch``.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np


class SwitchOnFlux:
    """Nuisance interface of :mod:`benchmark.core.nuisance` for the switch-on flux step."""

    #: Half-width of the switch-on flux searched, relative to the supply's flux amplitude
    #: ``V / w`` (the corrected switch-on leaves errors of about 1 % of it).
    SWITCH_ON_FLUX_RANGE = 0.25

    def _init_switch_on_flux(self) -> None:
        """A measured switch-on with switching steps (``StartupRecord.switch_on_sample``) gets
        two nuisance parameters, the alpha and beta stator flux step (V s) left by the error of
        its corrected volt-seconds: the voltage sample there gets ``flux / Ts`` added (with the
        record's hold, the added volt-seconds are ``flux``)."""
        from benchmark.problems.timedomain.problem import _supply_frequency  # (problem.py imports this module)

        self._v_measured = [(r[0], r[1]) for r in self._records]
        self._flux_at, names, bound = [], [], []
        many = len(self._records) > 1
        for j, rec in enumerate(self.dataset.startups):
            k = rec.switch_on_sample
            if k is None or not 0 < k < len(rec.t) - 1:
                continue
            self._flux_at.append((j, int(k)))
            v_a, v_b = self._v_measured[j]
            f0 = _supply_frequency(v_a[len(v_a) // 2:], v_b[len(v_b) // 2:], self.dataset.sample_time) or \
                self.dataset.supply_frequency or 50.0
            psi = float(np.max(np.hypot(v_a, v_b))) / (2.0 * math.pi * f0)
            suffix = f"[{j}]" if many else ""
            names += [f"switch_on_flux_alpha{suffix}", f"switch_on_flux_beta{suffix}"]
            bound += [self.SWITCH_ON_FLUX_RANGE * psi] * 2
        self.nuisance_names = tuple(names)
        self.nuisance_units = ("V s",) * len(names)
        self.nuisance_bound = np.asarray(bound, float)
        self.nuisance_values = np.zeros(len(names))

    def set_nuisance(self, eta) -> None:
        """Make the switch-on flux steps ``eta`` (V s, in :attr:`nuisance_names` order) part of
        the record's voltages from now on (cost, residuals, fit quality, figures)."""
        eta = np.asarray(eta, float)
        if eta.shape != (len(self.nuisance_names),):
            raise ValueError(f"nuisance: expected {len(self.nuisance_names)} values, got {eta.shape}")
        records = list(self._records)  # records without a switch-on step keep their voltages
        for n, (j, k) in enumerate(self._flux_at):
            v_a, v_b = self._v_measured[j][0].copy(), self._v_measured[j][1].copy()
            v_a[k] += eta[2 * n] / self.dataset.sample_time
            v_b[k] += eta[2 * n + 1] / self.dataset.sample_time
            records[j] = (v_a, v_b) + tuple(records[j][2:])
        self._records = records
        self.nuisance_values = eta.copy()

    def dataset_with_nuisance(self):
        """The data set with the switch-on flux steps set so far (:meth:`set_nuisance`) added to
        its voltages, for models fitted elsewhere (the diagnosis); unchanged without them."""
        if not self.nuisance_names or not np.any(self.nuisance_values):
            return self.dataset
        startups = list(self.dataset.startups)
        lines = []
        for n, (j, k) in enumerate(self._flux_at):
            v_a, v_b = self._records[j][0], self._records[j][1]
            startups[j] = replace(startups[j], v_alpha=v_a.copy(), v_beta=v_b.copy(), switch_on_sample=None)
            a, b = self.nuisance_values[2 * n:2 * n + 2]
            lines.append(f"switch-on flux step estimated with the motor's parameters: ({1e3 * a:+.4g}, {1e3 * b:+.4g}) "
                         f"mV s (alpha, beta), added to the voltage at t = {k * self.dataset.sample_time:.4f} s")
        return replace(self.dataset, startups=startups, conditioning=list(self.dataset.conditioning) + lines)

    def residuals_nuisance(self, X: np.ndarray, eta) -> np.ndarray:
        """:meth:`residuals_batch` of the candidates ``X`` with the switch-on flux steps ``eta``."""
        kept = self.nuisance_values.copy()
        self.set_nuisance(eta)
        try:
            return self.residuals_batch(X)
        finally:
            self.set_nuisance(kept)

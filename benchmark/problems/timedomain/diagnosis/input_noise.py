"""The measured voltage's noise, carried through the model into the residual's noise level.

The model is driven by the recorded voltages. Where these are measured continuous voltages
(a grid-fed start, ``input_hold: linear``), their noise is not in the motor (the motor saw
the true voltage) but it is in the simulated currents and speed: integrated by the machine's
transient inductance, a few tenths of a volt give a low-frequency current error that can
reach half the current sensor's own noise. Left out, the residual of the *true* parameters
sits 10-30 % above the noise level, and every such record looks like a gap nothing explains.

So the residual's noise level of each channel is ``sqrt(sensor^2 + propagated^2)``, with
``propagated`` the RMS change of the model's output when noise like the voltage's is added
to the voltages (a few realisations at the base identification). What the machine
integrates is the noise's low-frequency part, so the realisations must have the noise's
spectrum, not only its spread: each is the measured noise itself (the pre-trigger less its
mean, or what the steady state's harmonic fit leaves), circularly shifted by a random lag,
sign-flipped and repeated over the record; white noise only when neither exists. A
conditioning that turns point samples into interval means, for instance, colours the noise
(lag-one correlation -0.25), which a white realisation of the same spread would overstate
by a third. Its relative uncertainty is the voltage noise estimate's plus the realisations'
spread.
Inverter records (``zoh``: the switch-state voltages from the DC link and the gates) carry no
measurement noise and are left unchanged.
"""

from __future__ import annotations

import copy
import math
from dataclasses import replace

import numpy as np

from benchmark.core.noise_estimates import NoiseEstimate
from benchmark.problems.timedomain.diagnosis.fit import DiagnosisData, JointModel
from benchmark.problems.timedomain.noise import voltage_noise

#: Noise realisations added to the voltages.
REALISATIONS = 8
#: Seed of those realisations (fixed: the same data give the same noise level, bit for bit).
SEED = 20261124


def with_voltage_noise(data: DiagnosisData, model: JointModel, x: np.ndarray) -> tuple[DiagnosisData, dict | None]:
    """``data`` with each start-up channel's noise level raised by the measured voltage's noise
    carried through ``model`` at ``x`` (its base parameters), and a record of what was added
    (None when the voltages are not measured continuous signals)."""
    if not data.linear:
        return data, None
    speed = data.meas[2] if data.has_speed else None
    vn, templates = voltage_noise(data.t, data.v_alpha, data.v_beta, data.meas[0], data.meas[1], speed,
                                  data.supply_frequency)
    y0 = model.simulate(x[None, :])[0]
    rng = np.random.default_rng(SEED)
    n = data.n_startup
    slices = {ch: s for ch, s in data.channel_slices().items() if ch != "stop_speed"}
    power = {ch: [] for ch in slices}
    for _ in range(REALISATIONS):
        lag, sign = int(rng.integers(0, 1 << 30)), float(rng.choice([-1.0, 1.0]))
        extra = {ch: realisation(templates.get(ch), vn[ch].std, n, lag, sign, rng) for ch in ("v_alpha", "v_beta")}
        noisy = replace(data, v_alpha=data.v_alpha + extra["v_alpha"], v_beta=data.v_beta + extra["v_beta"])
        noisy_model = copy.copy(model)  # the same model, driven by the noisier voltages
        noisy_model.data = noisy
        y = noisy_model.simulate(x[None, :])[0]
        for ch, s in slices.items():
            d = y[s] - y0[s]
            power[ch].append(float(np.mean(d[np.isfinite(d)] ** 2)))
    u_v = max(vn["v_alpha"].rel_uncertainty, vn["v_beta"].rel_uncertainty)
    noise = dict(data.noise)
    added = {}
    for ch, p in power.items():
        p = np.asarray(p)
        var_p = float(np.mean(p))
        if not np.isfinite(var_p) or var_p <= 0.0:
            continue
        u_p = math.hypot(u_v, float(np.std(p)) / var_p / (2.0 * math.sqrt(len(p))))
        old = noise[ch]
        var = old.std**2 + var_p
        added[ch] = math.sqrt(var_p)
        noise[ch] = NoiseEstimate(math.sqrt(var), (old.std**2 * old.rel_uncertainty + var_p * u_p) / var,
                                  old.n_effective,
                                  f"{old.method}; with the measured voltage's noise through the model "
                                  f"({math.sqrt(var_p):.3g} of {math.sqrt(var):.3g})")
    record = {"voltage_std": {ch: float(v.std) for ch, v in vn.items()},
              "voltage_method": vn["v_alpha"].method + ("" if templates else "; white realisations"),
              "propagated_std": added,
              "realisations": REALISATIONS}
    return replace(data, noise=noise), record


def realisation(template: np.ndarray | None, std: float, n: int, lag: int, sign: float,
                rng: np.random.Generator) -> np.ndarray:
    """``n`` samples of noise of spread ``std``: ``template`` circularly shifted by ``lag``,
    times ``sign``, repeated to length ``n`` (white when there is no usable template). The same
    lag for both voltage channels keeps their cross-correlation."""
    if template is None or len(template) < 16 or not np.std(template) > 0:
        return std * rng.standard_normal(n)
    e = np.roll(np.asarray(template, float), lag % len(template))
    e = np.tile(e, -(-n // len(e)))[:n]
    return sign * std / float(np.std(e)) * e

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
measurement noise and are left unchanged. Part of the one noise estimate
(:mod:`benchmark.problems.timedomain.noise`): the identification's fit quality and the
diagnosis both raise their levels with :func:`with_propagated_voltage_noise`.
"""

from __future__ import annotations

import math

import numpy as np

from benchmark.core.noise_estimates import NoiseEstimate
from benchmark.problems.timedomain.noise import (
    MIN_QUIET,
    fallback,
    floored,
    modulated_periodic_noise,
    noise_from_quiet,
    quiet_pre_trigger_length,
    steady_start,
)

#: Noise realisations added to the voltages.
REALISATIONS = 8
#: Seed of those realisations (fixed: the same data give the same noise level, bit for bit).
SEED = 20261124


def voltage_noise(t, v_alpha, v_beta, i_alpha, i_beta, speed,
                  supply_frequency: float) -> tuple[dict[str, NoiseEstimate], dict[str, np.ndarray]]:
    """Noise of measured continuous voltages ``v_alpha``, ``v_beta`` (V), found as the currents'
    is: the pre-trigger's spread where there is one, else what the drifting-harmonics fit of the
    steady state leaves (the grid's harmonics, unbalance and slow dips are signal, not noise).
    Also returns that noise itself (the quiet segment less its mean, or the fit's residual),
    whose spectrum, not only its spread, decides what it does to the model (empty when the
    fourth-difference fallback was used)."""
    n = len(t)
    fs = 1.0 / float(np.median(np.diff(t)))
    v_floor = 1e-5 * float(np.max(np.hypot(v_alpha, v_beta)))
    chans = {"v_alpha": np.asarray(v_alpha, float), "v_beta": np.asarray(v_beta, float)}
    k_quiet = quiet_pre_trigger_length(v_alpha, v_beta, i_alpha, i_beta)
    out: dict[str, NoiseEstimate] = {}
    templates: dict[str, np.ndarray] = {}
    has_speed = speed is not None and bool(np.all(np.isfinite(speed)))
    k_ss = steady_start(speed if has_speed else None, n, max(int(fs / supply_frequency), 1))
    for ch, x in chans.items():
        try:
            if k_quiet >= MIN_QUIET:
                out[ch] = floored(noise_from_quiet(x[:k_quiet]), x[:k_quiet], v_floor)
                templates[ch] = x[:k_quiet] - np.mean(x[:k_quiet])
                continue
            if (n - k_ss) / fs * supply_frequency < 2:
                raise ValueError("steady state shorter than two periods")
            est, templates[ch] = modulated_periodic_noise(x[k_ss:], fs, supply_frequency)
            out[ch] = floored(est, x[k_ss:], v_floor)
        except (ValueError, np.linalg.LinAlgError) as exc:
            out[ch] = fallback(x, v_floor, str(exc))
    return out, templates


def with_propagated_voltage_noise(noise: dict[str, NoiseEstimate], simulate, t, v_alpha, v_beta, i_alpha,
                                  i_beta, speed, supply_frequency: float) -> tuple[dict[str, NoiseEstimate], dict]:
    """``noise`` (channel -> estimate) with each channel that ``simulate`` returns raised by the
    measured voltage's noise carried through the model: ``simulate(v_alpha, v_beta)`` gives the
    model's outputs ``{channel: array}`` for those voltages (the model at its identified
    parameters), ``v_alpha, v_beta`` (V) are the measured voltages, the other arrays the record's
    (for :func:`voltage_noise`). Returns the raised estimates and a record of what was added."""
    vn, templates = voltage_noise(t, v_alpha, v_beta, i_alpha, i_beta, speed, supply_frequency)
    y0 = simulate(v_alpha, v_beta)
    rng = np.random.default_rng(SEED)
    n = len(v_alpha)
    power = {ch: [] for ch in y0}
    for _ in range(REALISATIONS):
        lag, sign = int(rng.integers(0, 1 << 30)), float(rng.choice([-1.0, 1.0]))
        extra = {ch: realisation(templates.get(ch), vn[ch].std, n, lag, sign, rng) for ch in ("v_alpha", "v_beta")}
        y = simulate(v_alpha + extra["v_alpha"], v_beta + extra["v_beta"])
        for ch in y0:
            d = y[ch] - y0[ch]
            power[ch].append(float(np.mean(d[np.isfinite(d)] ** 2)))
    u_v = max(vn["v_alpha"].rel_uncertainty, vn["v_beta"].rel_uncertainty)
    noise = dict(noise)
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
    return noise, record


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

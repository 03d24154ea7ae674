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
spread: the record's own voltage noise is one realisation, whose effect on the currents varies about the
realisations' mean by that spread (a cold user's grid starts: 0.020-0.027 A across noise draws where the
spread of the mean alone, a third of it, claimed +-2 %).
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
    whose spectrum, not only its spread, decides what it does to the model, each with the share of
    a white noise's power it keeps at each frequency of its FFT (None for a quiet segment; for a
    fit's residual, :func:`~benchmark.problems.timedomain.noise.residual_share`); empty when the
    fourth-difference fallback was used."""
    n = len(t)
    fs = 1.0 / float(np.median(np.diff(t)))
    v_floor = 1e-5 * float(np.max(np.hypot(v_alpha, v_beta)))
    chans = {"v_alpha": np.asarray(v_alpha, float), "v_beta": np.asarray(v_beta, float)}
    k_quiet = quiet_pre_trigger_length(t, v_alpha, v_beta, i_alpha, i_beta)
    out: dict[str, NoiseEstimate] = {}
    templates: dict[str, np.ndarray] = {}
    shares: dict[str, np.ndarray] = {}
    has_speed = speed is not None and bool(np.all(np.isfinite(speed)))
    k_ss = steady_start(speed if has_speed else None, n, max(int(fs / supply_frequency), 1))
    for ch, x in chans.items():
        try:
            if k_quiet:
                out[ch] = floored(noise_from_quiet(x[:k_quiet]), x[:k_quiet], v_floor)
                templates[ch] = x[:k_quiet] - np.mean(x[:k_quiet])
                continue
            if (n - k_ss) / fs * supply_frequency < 2:
                raise ValueError("steady state shorter than two periods")
            est, templates[ch], shares[ch] = modulated_periodic_noise(x[k_ss:], fs, supply_frequency)
            out[ch] = floored(est, x[k_ss:], v_floor)
        except (ValueError, np.linalg.LinAlgError) as exc:
            out[ch] = fallback(x, v_floor, str(exc))
    return out, {ch: (e, shares.get(ch)) for ch, e in templates.items()}


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
    shape = spectral_shape([templates.get(ch) for ch in ("v_alpha", "v_beta")], n, float(np.median(np.diff(t))))
    for _ in range(REALISATIONS):
        extra = realisation(shape, [vn["v_alpha"].std, vn["v_beta"].std], n, rng)
        y = simulate(v_alpha + extra[0], v_beta + extra[1])
        for ch in y0:
            d = y[ch] - y0[ch]
            power[ch].append(float(np.mean(d[np.isfinite(d)] ** 2)))
    u_v = max(vn["v_alpha"].rel_uncertainty, vn["v_beta"].rel_uncertainty)
    noise = dict(noise)
    added, uncertainties = {}, {}
    for ch, p in power.items():
        p = np.asarray(p)
        var_p = float(np.mean(p))
        if not np.isfinite(var_p) or var_p <= 0.0:
            continue
        # the record's propagated power is one realisation: it varies about the realisations' mean by their
        # spread (relative spread of the power, half that of its root), and that mean is known to 1/sqrt(n)
        spread = float(np.std(p)) / var_p / 2.0
        u_p = math.hypot(u_v, spread * math.sqrt(1.0 + 1.0 / len(p)))
        old = noise[ch]
        var = old.std**2 + var_p
        added[ch] = math.sqrt(var_p)
        uncertainties[ch] = u_p
        noise[ch] = NoiseEstimate(math.sqrt(var), (old.std**2 * old.rel_uncertainty + var_p * u_p) / var,
                                  old.n_effective,
                                  f"{old.method}; with the measured voltage's noise through the model "
                                  f"({math.sqrt(var_p):.3g} of {math.sqrt(var):.3g})")
    record = {"voltage_std": {ch: float(v.std) for ch, v in vn.items()},
              "voltage_method": vn["v_alpha"].method + ("" if templates else "; white realisations"),
              "propagated_std": added,
              "propagated_rel_uncertainty": uncertainties,
              "realisations": REALISATIONS}
    return noise, record


#: Width of the running median that smooths the noise's periodogram (:func:`spectral_shape`), Hz:
#: wide beside the bands a drifting-harmonics fit removes (a few Hz about DC and each harmonic it
#: kept), narrow beside the spectrum's own changes (a conditioning's filter, a probe's roll-off).
SMOOTHING_HZ = 200.0


def spectral_shape(templates: list, n: int, sample_time: float) -> np.ndarray | None:
    """The voltage noise's spectral matrix on the ``n``-sample record's frequency grid, from the
    measured noise ``templates`` (per voltage channel ``(noise, share)`` from :func:`voltage_noise`,
    or None; ``sample_time`` in s): (n//2 + 1, 2, 2), each bin's Cholesky factor of the two
    channels' smoothed auto- and cross-spectra, normalised so that unit white noise has the
    identity; None where there is no usable template (white realisations).

    Smoothed, not the template itself: where the noise came from a drifting-harmonics fit of the
    steady state, the fit has taken out the bands about DC and each harmonic it kept, and a
    realisation that repeats the template lacks them. Those are the bands the machine turns into
    current error (near DC the stator sees only its resistance and the leakage): on an
    independent-plant 5 hp grid start with 0.87 V of white noise per phase (plant seed 442 set 0,
    effect-free), the template's realisations carried 0.039 A into each current where the noise
    really carried 0.045-0.048 A, and the record sat 11 % above the noise band, `unexplained`.
    Each periodogram ordinate is divided by the share of the noise's power the fit left there
    (``share``), the bins it took almost all of left out, and each auto-spectrum is the running
    median of the rest over :data:`SMOOTHING_HZ` (divided by ln 2, the median of an ordinate
    over its mean: a spectral line the fit left does not move it); the coherence of the two
    channels is the running mean of their cross-spectrum over the same width, so that channels
    made from the same probes (line-to-line voltages) stay correlated."""
    if any(t is None or len(t[0]) < 16 or not np.std(t[0]) > 0 for t in templates):
        return None
    m = min(len(t[0]) for t in templates)
    X, auto = [], []
    width = max(int(round(SMOOTHING_HZ * m * sample_time)), 3)  # bins of 1 / (m sample_time) Hz
    for e, share in templates:
        x = np.fft.rfft(np.asarray(e, float)[:m] - np.mean(e[:m]))
        p = np.abs(x) ** 2
        kept = np.ones(len(p)) if share is None or len(share) != len(p) else np.asarray(share, float)
        p = np.where(kept > MIN_SHARE, p / np.maximum(kept, MIN_SHARE), np.nan)
        X.append(x)
        auto.append(_running(p, width, np.nanmedian) / math.log(2.0))
    cross = _running(X[0] * np.conj(X[1]), width, np.mean)
    norm = np.sqrt(_running(np.abs(X[0]) ** 2, width, np.mean) * _running(np.abs(X[1]) ** 2, width, np.mean))
    rho = np.where(norm > 0, cross / np.maximum(norm, 1e-300), 0.0)
    rho = rho / np.maximum(1.0, np.abs(rho))
    f_t = np.fft.rfftfreq(m)  # cycles per sample
    f_n = np.fft.rfftfreq(n)
    s_a, s_b = (np.interp(f_n, f_t, a) for a in auto)
    r = np.interp(f_n, f_t, rho.real) + 1j * np.interp(f_n, f_t, rho.imag)
    s_a, s_b = s_a / max(float(np.mean(s_a)), 1e-300), s_b / max(float(np.mean(s_b)), 1e-300)
    L = np.zeros((len(f_n), 2, 2), complex)
    L[:, 0, 0] = np.sqrt(s_a)
    L[:, 1, 0] = np.sqrt(s_b) * np.conj(r)
    L[:, 1, 1] = np.sqrt(s_b) * np.sqrt(np.maximum(1.0 - np.abs(r) ** 2, 0.0))
    return L


#: A periodogram ordinate whose bin kept less than this share of the noise's power (the fit took
#: the rest) is left out of the smoothed spectrum: too little is left there to scale back.
MIN_SHARE = 0.1


def _running(x: np.ndarray, width: int, stat) -> np.ndarray:
    """``stat`` (a reduction along axis 1) of ``x`` over a window of ``width`` bins about each
    bin, the window shortened at the ends."""
    half = width // 2
    pad = np.concatenate([x[half:0:-1], x, x[-2:-half - 2:-1]]) if half else x
    windows = np.lib.stride_tricks.sliding_window_view(pad, 2 * half + 1)
    return stat(windows, axis=1)


def realisation(shape: np.ndarray | None, std: list[float], n: int, rng: np.random.Generator) -> np.ndarray:
    """Two channels (2, n) of noise with the spectral matrix ``shape`` (:func:`spectral_shape`),
    each of spread ``std[k]``; white when ``shape`` is None."""
    z = rng.standard_normal((2, n))
    if shape is None:
        return np.asarray(std, float)[:, None] * z
    Z = np.fft.rfft(z, axis=1)
    Y = np.einsum("fij,jf->if", shape, Z)
    e = np.fft.irfft(Y, n, axis=1)
    return np.asarray(std, float)[:, None] / np.std(e, axis=1, keepdims=True) * e

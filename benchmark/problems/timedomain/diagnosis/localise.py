"""Where the base model misses (the ``localisation`` of the diagnosis document): shares of
the held-out residual's energy by channel and by segment of the experiment, the current
residual's harmonics in the steady state, and the time windows of the excess."""

from __future__ import annotations

import numpy as np

from benchmark.problems.timedomain.diagnosis.fit import DiagnosisData
from benchmark.problems.timedomain.diagnosis.folds import segment_masks

HARMONIC_ORDERS = (-11, -7, -5, -1, 1, 5, 7, 11, 13)


def localise(data: DiagnosisData, r: np.ndarray, band_hi: float) -> dict:
    """Where the residual ``r`` (noise-normalised) lies: shares by channel and segment, the
    current residual's harmonics, and the time windows of the excess (where its smoothed
    square, over one supply period, exceeds the noise band)."""
    e = r**2
    total = float(e.sum()) or 1.0
    by_channel = {ch: float(e[s].sum() / total) for ch, s in data.channel_slices().items()}
    segs = segment_masks(data)
    by_segment = {k: float(e[m].sum() / total) for k, m in segs.items()}
    n = data.n_startup
    ss = segs["steady_state"][:n]
    sl = data.channel_slices()
    spectrum = {}
    if ss.sum() > 64:
        res_i = (r[sl["i_alpha"]] * data.sigma["i_alpha"] + 1j * r[sl["i_beta"]] * data.sigma["i_beta"])[ss]
        tt = data.t[ss]
        for h in HARMONIC_ORDERS:
            spectrum[str(h)] = float(abs(np.mean(res_i * np.exp(-1j * 2 * np.pi * h * data.supply_frequency * tt))))
    # time windows of the excess over the start-up
    chans = [s for ch, s in sl.items() if ch != "stop_speed"]
    et = np.mean([e[s] for s in chans], axis=0)
    period = max(int(round(1.0 / (data.supply_frequency * data.sample_time))), 1)
    smooth = np.convolve(et, np.ones(period) / period, mode="same")
    above = smooth > band_hi**2
    windows = []
    if above.any():
        idx = np.flatnonzero(above)
        cuts = np.flatnonzero(np.diff(idx) > period) + 1
        for run in np.split(idx, cuts):
            if len(run) < period // 2:
                continue
            excess = float(np.sum(smooth[run] - 1.0))
            windows.append({"start_s": float(data.t[run[0]]), "end_s": float(data.t[run[-1]]),
                            "excess_share": excess})
        tot = sum(w["excess_share"] for w in windows) or 1.0
        for w in windows:
            w["excess_share"] = w["excess_share"] / tot
        windows.sort(key=lambda w: -w["excess_share"])
    stop = None
    if "stop_speed" in sl:
        es = e[sl["stop_speed"]]
        stop = {"chi2_per_residual": float(np.mean(es)), "above_band": bool(np.mean(es) > band_hi**2)}
    main = windows[0] if windows else None
    text = (f"the excess starts at t = {main['start_s']:.3g} s and ends at {main['end_s']:.3g} s "
            f"({100 * main['excess_share']:.0f} % of the start-up's excess)" if main else
            "no part of the start-up exceeds the noise band")
    if stop and stop["above_band"]:
        text += "; the free stop exceeds it too"
    return {"chi2_per_residual": float(e.sum() / len(e)), "by_channel": by_channel, "by_segment": by_segment,
            "current_residual_harmonics_A": spectrum, "excess_windows": windows[:5], "excess_window": main,
            "stop_record": stop, "summary": text}

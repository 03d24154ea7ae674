"""Figures of a diagnosis: the residual map and the fit before and after the verdict, where
the misfit is (the time window of the excess)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from benchmark.core.plotting import new_figure

LABELS = {"i_alpha": "i_alpha residual / noise", "i_beta": "i_beta residual / noise",
          "speed": "speed residual / noise", "stop_speed": "stop speed residual / noise"}
UNITS = {"i_alpha": "i_alpha (A)", "i_beta": "i_beta (A)", "speed": "speed (rad/s)"}


def _window(doc: dict, t: np.ndarray, f_supply: float) -> tuple[float, float]:
    """The main excess window padded by two supply periods (the first 0.3 s without one)."""
    w = doc["localisation"].get("excess_window")
    if not w:
        return float(t[0]), float(min(t[0] + 0.3, t[-1]))
    pad = 2.0 / f_supply
    a, b = w["start_s"] - pad, w["end_s"] + pad
    if b - a > 0.4:  # long windows: show the start of the excess, where it is first seen
        b = a + 0.4
    return float(max(a, t[0])), float(min(b, t[-1]))


def diagnosis_figures(models: dict, doc: dict, outdir: Path) -> list[str]:
    base_fit, final = models["base"], models["final"]
    base = base_fit.model
    data = base.data
    verdict = doc["verdict"]
    files = []
    x_base = 0.5 * (base_fit.xs["A"] + base_fit.xs["B"])
    aug = None
    if doc["effects"]:
        aug = (final.model, models["full_x"] if models["full_x"] is not None else 0.5 * (final.xs["A"] + final.xs["B"]))
    sl = data.channel_slices()
    band = models["band"]

    # residual map: held-out normalised residual against time, per channel, before and after
    fig, axes = new_figure(len(sl), 1, figsize=(9, 2.2 * len(sl)), sharex=False)
    for ax, (ch, s) in zip(np.atleast_1d(axes), sl.items(), strict=False):
        t = data.t if ch != "stop_speed" else data.stop_t
        ax.plot(t, base_fit.held[s], lw=0.5, label="base model (held out)")
        if aug is not None:
            ax.plot(t, final.held[s], lw=0.5, alpha=0.8, label=f"base + {verdict} (held out)")
        ax.axhspan(-band, band, color="0.85", zorder=0, label="noise band")
        ax.set_ylabel(LABELS[ch], fontsize=8)
        ax.set_xlabel("time (s)" + (" from the start of the free motion" if ch == "stop_speed" else ""))
        ax.grid(alpha=0.3)
    np.atleast_1d(axes)[0].legend(fontsize=7, loc="lower left", bbox_to_anchor=(0.0, 1.02), ncol=3, frameon=False)
    fig.suptitle(f"Residual map (verdict: {verdict}, {doc['status'].replace('_', ' ')})", y=1.0)
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(outdir / f"residual_map.{ext}", dpi=110, bbox_inches="tight")
        files.append(f"residual_map.{ext}")

    # fit before and after where the misfit is: (top) the channel that misses most, measured
    # and both models, around the peak of the excess; (bottom) the smoothed squared held-out
    # residual over the noise against time, with the noise band and the excess window shaded
    sim0 = base.simulate(np.atleast_2d(x_base))[0]
    sim1 = aug[0].simulate(np.atleast_2d(aug[1]))[0] if aug is not None else None
    share = doc["localisation"]["by_channel"]
    start_chans = [c for c in sl if c != "stop_speed"]
    ch = max(start_chans, key=lambda c: share.get(c, 0.0))
    s_ch = sl[ch]
    period = max(int(round(1.0 / (data.supply_frequency * data.sample_time))), 1)
    kernel = np.ones(period) / period
    e0 = np.convolve(np.mean([base_fit.held[sl[c]] ** 2 for c in start_chans], axis=0), kernel, mode="same")
    e1 = (np.convolve(np.mean([final.held[sl[c]] ** 2 for c in start_chans], axis=0), kernel, mode="same")
          if aug is not None else None)
    w = doc["localisation"].get("excess_window")
    k_peak = int(np.argmax(e0))
    if w:
        inside = (data.t >= w["start_s"]) & (data.t <= w["end_s"])
        k_peak = int(np.flatnonzero(inside)[np.argmax(e0[inside])]) if inside.any() else k_peak
    half = 3 * period
    zoom = slice(max(k_peak - half, 0), min(k_peak + half, data.n_startup))
    row_of = {"i_alpha": 0, "i_beta": 1, "speed": 2}
    fig, (a1, a2) = new_figure(2, 1, figsize=(10, 6.5))
    a1.plot(data.t[zoom], data.meas[row_of[ch]][zoom], "k.", ms=2, label="measured")
    a1.plot(data.t[zoom], sim0[s_ch][zoom], lw=1.0, label="base model")
    if sim1 is not None:
        a1.plot(data.t[zoom], sim1[s_ch][zoom], "--", lw=1.0, label=f"base + {verdict}")
    a1.set_xlabel("time (s)")
    a1.set_ylabel(UNITS[ch])
    a1.set_title(f"{ch} around the largest excess (t = {data.t[k_peak]:.3g} s)", fontsize=9)
    a1.grid(alpha=0.3)
    a1.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    a2.semilogy(data.t, np.maximum(e0, 1e-3), lw=1.0, label="base model")
    if e1 is not None:
        a2.semilogy(data.t, np.maximum(e1, 1e-3), lw=1.0, label=f"base + {verdict}")
    a2.axhline(band**2, color="0.4", ls=":", lw=1.0, label="noise band (upper)")
    for win in doc["localisation"].get("excess_windows", []):
        a2.axvspan(win["start_s"], win["end_s"], color="tab:red", alpha=0.08)
    a2.set_xlabel("time (s)")
    a2.set_ylabel("held-out residual^2 / noise^2\n(one-period mean)")
    a2.grid(alpha=0.3, which="both")
    a2.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    where = (f"excess from t = {w['start_s']:.3g} s to {w['end_s']:.3g} s" if w else "no excess above the noise band")
    fig.suptitle(f"Fit before and after ({verdict}) where the base model misses: {where}", fontsize=10)
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(outdir / f"fit_before_after.{ext}", dpi=110, bbox_inches="tight")
        files.append(f"fit_before_after.{ext}")
    return files

"""Figures of a diagnosis: the residual map and the fit before and after the verdict."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from benchmark.core.plotting import new_figure

LABELS = {"i_alpha": "i_alpha residual / noise", "i_beta": "i_beta residual / noise",
          "speed": "speed residual / noise", "stop_speed": "stop speed residual / noise"}


def diagnosis_figures(models: dict, doc: dict, outdir: Path) -> list[str]:
    base, x_base = models["base"]
    data = base.data
    verdict = doc["verdict"]
    aug = models["fitted"].get(verdict)
    files = []

    # residual map: normalised residual against time, per channel, before (and after)
    sl = data.channel_slices()
    fig, axes = new_figure(len(sl), 1, figsize=(9, 2.2 * len(sl)), sharex=False)
    r0 = base.residuals(np.atleast_2d(x_base))[0]
    r1 = None
    if aug is not None:
        model, xs = aug
        r1 = model.residuals(np.atleast_2d(xs["A"]))[0]
    for ax, (ch, s) in zip(np.atleast_1d(axes), sl.items(), strict=False):
        t = data.t if ch != "stop_speed" else data.stop_t
        ax.plot(t, r0[s], lw=0.5, label="base model")
        if r1 is not None:
            ax.plot(t, r1[s], lw=0.5, alpha=0.8, label=f"base + {verdict}")
        ax.set_ylabel(LABELS[ch], fontsize=8)
        ax.set_xlabel("time (s)" + (" from the start of the free motion" if ch == "stop_speed" else ""))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    fig.suptitle(f"Residual map (verdict: {verdict})")
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(outdir / f"residual_map.{ext}", dpi=110)
        files.append(f"residual_map.{ext}")

    # fit before and after: early start-up speed and current
    n = data.n_startup
    sim0 = base.simulate(np.atleast_2d(x_base))[0]
    sim1 = aug[0].simulate(np.atleast_2d(aug[1]["A"]))[0] if aug is not None else None
    fig, (a1, a2) = new_figure(2, 1, figsize=(9, 6))
    early = data.t <= min(0.3, data.t[-1])
    a1.plot(data.t[early], data.meas[2][early], "k.", ms=1.5, label="measured")
    a1.plot(data.t[early], sim0[2 * n:3 * n][early], label="base model")
    if sim1 is not None:
        a1.plot(data.t[early], sim1[2 * n:3 * n][early], "--", label=f"base + {verdict}")
    a1.set_xlabel("time (s)")
    a1.set_ylabel("speed (rad/s)")
    a1.legend()
    a1.grid(alpha=0.3)
    a2.plot(data.t[early], data.meas[0][early], "k.", ms=1.5, label="measured")
    a2.plot(data.t[early], sim0[:n][early], lw=0.8, label="base model")
    if sim1 is not None:
        a2.plot(data.t[early], sim1[:n][early], "--", lw=0.8, label=f"base + {verdict}")
    a2.set_xlabel("time (s)")
    a2.set_ylabel("i_alpha (A)")
    a2.legend()
    a2.grid(alpha=0.3)
    fig.suptitle("Start-up fit before and after the diagnosed effect")
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(outdir / f"fit_before_after.{ext}", dpi=110)
        files.append(f"fit_before_after.{ext}")
    return files

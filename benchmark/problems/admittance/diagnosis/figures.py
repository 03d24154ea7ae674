"""Figures of the slip-sweep diagnosis: measured and model admittance before and after the chosen
effects, and the residual by region of slip."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def sweep_figures(models: dict, doc: dict, outdir) -> list[str]:
    """``residual_map.png`` (G, B residual over noise against slip, per voltage level, before and
    after the verdict's augmentation) and ``fit.png`` (measured G, B with both models)."""
    from benchmark.core.plotting import new_figure

    base, x_base = models["base"]
    aug = models["fitted"].get(doc["verdict"])
    d = base.data
    files = []
    fig, axes = new_figure(2, 1, figsize=(9, 6), sharex=True)
    e0 = base.residual_complex(x_base)
    e1 = aug[0].residual_complex(aug[1]) if aug is not None else None
    for ax, comp, name in ((axes[0], np.real, "G"), (axes[1], np.imag, "B")):
        for j, v in enumerate(d.levels):
            m = d.level == j
            order = np.argsort(d.s[m])
            ax.plot(d.s[m][order], comp(e0[m])[order], ".-", lw=0.6, ms=3, label=f"base, {v:.3g} V")
            if e1 is not None:
                ax.plot(d.s[m][order], comp(e1[m])[order], "x", ms=3, label=f"+ {doc['verdict']}, {v:.3g} V")
        for b in (1.0, 0.0):
            ax.axvline(b, color="0.6", lw=0.5)
        ax.set_ylabel(f"{name} residual / noise")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=6, ncol=2)
    axes[1].set_xlabel("slip")
    axes[0].set_title(
        f"Residual map: braking s > 1, motoring, near synchronism, generating s < 0; verdict {doc['verdict']}",
        fontsize=8,
    )
    fig.tight_layout()
    fig.savefig(Path(outdir) / "residual_map.png", dpi=120)
    files.append("residual_map.png")

    fig, axes = new_figure(2, 1, figsize=(9, 6), sharex=True)
    Y0 = base.admittance(x_base)
    Y1 = aug[0].admittance(aug[1]) if aug is not None else None
    for ax, comp, name in ((axes[0], np.real, "G (S)"), (axes[1], np.imag, "B (S)")):
        m = d.level == len(d.levels) - 1
        order = np.argsort(d.s[m])
        ax.plot(d.s[m][order], comp(d.Y[m])[order], "k.", ms=4, label=f"measured, {d.levels[-1]:.3g} V")
        ax.plot(d.s[m][order], comp(Y0[m])[order], "-", lw=1, label="base")
        if Y1 is not None:
            ax.plot(d.s[m][order], comp(Y1[m])[order], "--", lw=1, label=f"+ {doc['verdict']}")
        ax.set_ylabel(name)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    axes[1].set_xlabel("slip")
    fig.tight_layout()
    fig.savefig(Path(outdir) / "fit.png", dpi=120)
    files.append("fit.png")
    return files

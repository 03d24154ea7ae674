"""Figures of a time-domain run: measured against simulated currents and speed over the whole
start-up and over its first 100 ms (Alonge et al. Figs. 16-20), and, when the data set has a
stop record, the free stop with the case-1 and case-2 fits (Fig. 14). Drawn by
:func:`benchmark.core.plotting.write_run_figures` through :meth:`TimeDomainProblem.plots`."""

from __future__ import annotations

import functools
from collections.abc import Callable
from pathlib import Path

import numpy as np

from benchmark.core.plotting import MEASURED, MODEL, ZOOM_S, Plot, envelope, rms

# -- time domain -------------------------------------------------------------------------------
CHANNELS = (("i_alpha", "i_alpha (A)", "A"), ("i_beta", "i_beta (A)", "A"), ("speed", "speed (rad/s)", "rad/s"))


def timedomain_plots(problem, x: np.ndarray | None, record: dict) -> list[Plot]:
    plots = []
    ds = problem.dataset
    if x is not None:
        sims: list = []

        def simulated(j: int) -> dict:
            """Record j simulated with the estimate (all records in one call, made on first use, so
            that a failing simulation costs the start-up figures only)."""
            if not sims:
                sims.extend(problem.simulate(np.atleast_2d(np.asarray(x, float))))
            return {"i_alpha": sims[j][0, 0], "i_beta": sims[j][0, 1], "speed": sims[j][0, 2]}

        many = len(ds.startups) > 1
        for j, rec in enumerate(ds.startups):
            suffix = f"_{j + 1}" if many else ""
            src = Path(rec.source).name if rec.source != "memory" else "synthetic record"
            meas = {"i_alpha": rec.i_alpha, "i_beta": rec.i_beta, "speed": rec.speed}
            simd = functools.partial(simulated, j)
            plots.append(Plot(
                f"startup{suffix}", f"Start-up{' ' + str(j + 1) if many else ''}: measured and simulated",
                f"Measured ({src}) and simulated currents and speed over the whole start-up with the "
                "identified parameters (Alonge et al. Figs. 16-20); the RMS misfit of each channel is above its "
                "panel.",
                _startup_drawer(rec.t, meas, simd, None, src), size=(9.0, 7.5)))
            plots.append(Plot(
                f"startup_zoom{suffix}", f"Start-up{' ' + str(j + 1) if many else ''}: the first 100 ms",
                "The same over the first 100 ms, where the electrical transient and the start of the "
                "acceleration show most clearly (Alonge et al. Figs. 17-20).",
                _startup_drawer(rec.t, meas, simd, ZOOM_S, src), size=(9.0, 7.5)))
    if ds.stops:
        stop = ds.stops[0]
        used = problem.mechanical.case if problem.mechanical is not None else None
        plots.append(Plot(
            "stop", "Free stop: case-1 and case-2 fits",
            "The free-stop speed with the exponential fit that neglects Coulomb friction (case 1: tau_m "
            "at the w0/e time) and the fit with Coulomb friction (case 2) (Alonge et al. Fig. 14); "
            + (f"the identification used case {used}." if used else "the identification did not use it."),
            _stop_drawer(stop, used)))
    return plots


def _startup_drawer(t, meas: dict, simulated: Callable[[], dict], zoom: float | None, src: str):
    def draw(fig):
        sim = simulated()
        axes = fig.subplots(3, 1, sharex=True)
        sel = t <= zoom if zoom is not None else slice(None)
        tt = t[sel]
        for ax, (key, label, unit) in zip(axes, CHANNELS, strict=True):
            m, s = meas[key][sel], sim[key][sel]
            finite = np.isfinite(s)
            if zoom is not None:
                ax.plot(tt, m, ".", color=MEASURED, ms=2.0, label="measured")
            else:
                # a broad grey band under a thin model line: both stay visible where they agree
                ax.plot(*envelope(tt, m), color="0.6", lw=2.4, label="measured")
            ax.plot(*envelope(tt, s), color=MODEL, lw=0.9, label="simulated (identified model)")
            ax.set_ylabel(label)
            note = f"RMS misfit {rms(m, s):.3g} {unit}"
            if not finite.all():
                k = int(np.argmin(finite))
                note = f"the simulation diverged at t = {tt[k]:.4g} s" + (f" ({note} before)" if k >= 10 else "")
            ax.set_title(note, loc="right", fontsize=8)
            ax.grid(alpha=0.3)
        axes[-1].set_xlabel("time from switch-on (s)")
        what = "first 100 ms of the start-up" if zoom is not None else "start-up"
        fig.suptitle(f"Measured and simulated {what} ({src}; Alonge et al. Figs. 16-20)", fontsize=11)
        fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncols=2, fontsize=9,
                   markerscale=3)
    return draw


def _stop_drawer(stop, used_case: int | None):
    from benchmark.problems.timedomain.mechanical import fit_free_stop

    def draw(fig):
        ax = fig.subplots()
        t_free = None
        for case, color, style in ((1, "C0", "--"), (2, "C1", "-")):
            try:
                est = fit_free_stop(stop.t, stop.speed, case=case, source=stop.source)
            except Exception as exc:  # a stop the fit refuses: say so in the legend
                ax.plot([], [], color=color, ls=style, label=f"case {case}: no fit ({exc})")
                continue
            t_free = est.t_free
            tt = np.linspace(0.0, float(stop.t[-1]) - est.t_free, 600)
            what = (f"case 1, no Coulomb friction: tau_m = {est.tau_m:.4g} s" if case == 1 else
                    f"case 2, with Coulomb friction: tau_m = {est.tau_m:.4g} s, "
                    f"fc/J = {est.fc_over_J:.4g} rad/s$^2$")
            if case == used_case:
                what += " (used)"
            ax.plot(tt + est.t_free, est.free_motion(tt), color=color, ls=style, lw=2.0, label=what)
        # the measurement on top, thin, so that it stays visible where a fit follows it
        ax.plot(*envelope(stop.t, stop.speed), color=MEASURED, lw=0.7, label="measured speed", zorder=3)
        if t_free is not None:
            ax.axvline(t_free, color="0.5", ls=":", lw=1.0,
                       label=f"free motion from {t_free:.3g} s (electrical transient over)")
        ax.set_xlabel("time from supply removal (s)")
        ax.set_ylabel("speed (rad/s)")
        ax.set_ylim(bottom=min(0.0, float(np.nanmin(stop.speed))) - 5)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
        ax.set_title("Free stop: exponential (case 1) and Coulomb + viscous (case 2) fits (Alonge et al. Fig. 14)",
                     fontsize=10)
    return draw



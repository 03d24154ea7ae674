"""Figures of one run, saved beside its ``result.json`` (PNG and SVG) and listed in ``report.md``.

Which figures a run gets depends on its problem (chosen by ``problem.name``):

* ``timedomain``: measured against simulated currents and speed over the whole start-up and
  over its first 100 ms (Alonge et al. Figs. 16-20), and, when the data set has a stop record,
  the free stop with the case-1 and case-2 fits (Fig. 14);
* ``admittance``: conductance and susceptance against speed, stator current and power factor
  against speed (Lindsay and Barton Figs. 11-13), and torque against speed (measured and model
  when the data have a torque column, else the model alone);
* every problem: convergence, the best cost against the evaluations (``history.csv``).

The harness calls :func:`write_run_figures` once the result is safely written; each figure is
drawn on its own, so one that fails (listed under ``errors``) does not cost the others. Long
records are reduced before drawing to a min/max envelope of about one bin per pixel column
(:func:`envelope`), which draws the same picture from a few thousand points, so a figure costs
well under a second and an SVG stays a few hundred kB. Matplotlib is used through its object
interface (no pyplot, no global backend switch), so making figures has no side effect on the
process. The SVG files carry no date, so the same run gives the same files.
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["Plot", "envelope", "figure_plots", "write_run_figures", "write_report", "REPORT_NAME"]

REPORT_NAME = "report.md"
DPI = 110
#: Bins of the min/max envelope of a long record (a bit more than the axes' width in pixels).
ENVELOPE_BINS = 1000
#: The zoom on the start of the start-up (Alonge et al. Figs. 17-20 show the first 100 ms).
ZOOM_S = 0.1
MEASURED = "k"
MODEL = "C1"


@dataclass
class Plot:
    """One figure: file stem, title (for the report), caption and the function that draws it
    on a fresh :class:`matplotlib.figure.Figure` of size ``size`` (inches)."""

    name: str
    title: str
    caption: str
    draw: Callable
    size: tuple[float, float] = (9.0, 4.5)
    files: list[str] = field(default_factory=list)


# -- drawing helpers ---------------------------------------------------------------------------
def envelope(t: np.ndarray, y: np.ndarray, bins: int = ENVELOPE_BINS) -> tuple[np.ndarray, np.ndarray]:
    """``(t, y)`` reduced to at most about ``2 bins`` points that draw the same line: for each
    bin of consecutive samples its smallest and largest value, in time order. Short records
    are returned as they are; non-finite values (a diverged simulation) stay gaps."""
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    n = len(y)
    if n <= 2 * bins:
        return t, y
    k = int(math.ceil(n / bins))
    m = (n // k) * k
    Y = y[:m].reshape(-1, k)
    finite = np.isfinite(Y)
    lo = np.argmin(np.where(finite, Y, np.inf), axis=1)
    hi = np.argmax(np.where(finite, Y, -np.inf), axis=1)
    idx = np.sort(np.stack([lo, hi], axis=1), axis=1) + (np.arange(len(Y)) * k)[:, None]
    idx = np.concatenate([idx.ravel(), np.arange(m, n)])
    return t[idx], y[idx]


def _rms(a: np.ndarray, b: np.ndarray) -> float:
    d = np.asarray(a, float) - np.asarray(b, float)
    d = d[np.isfinite(d)]
    return float(np.sqrt(np.mean(d * d))) if len(d) else math.nan


def _save(fig, outdir: Path, name: str) -> list[str]:
    import matplotlib

    files = []
    with matplotlib.rc_context({"svg.hashsalt": "imbench"}):
        for ext in ("png", "svg"):
            path = outdir / f"{name}.{ext}"
            meta = {"Date": None} if ext == "svg" else None
            fig.savefig(path, dpi=DPI, metadata=meta)
            files.append(path.name)
    return files


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
            note = f"RMS misfit {_rms(m, s):.3g} {unit}"
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
    from benchmark.costs.mechanical import fit_free_stop

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


# -- admittance --------------------------------------------------------------------------------
def admittance_plots(problem, x: np.ndarray | None, record: dict) -> list[Plot]:
    if x is None:
        return []
    curves = _admittance_curves(problem, np.asarray(x, float))
    d = problem.data
    err = problem.rms_error_percent(np.asarray(x, float))
    n_sync = 60.0 * d.frequency / d.pole_pairs
    has_torque = d.torque is not None
    return [
        Plot("admittance", "Admittance against speed",
             "Measured (points) and model (lines) input conductance G and susceptance B per phase against "
             f"speed (Lindsay and Barton Figs. 11-13); RMS misfit {err:.3g} % of full scale.",
             _adm_drawer(curves, n_sync, err, "admittance"), size=(9.0, 6.5)),
        Plot("current_power_factor", "Current and power factor against speed",
             "Stator current (RMS per phase, at each reading's voltage) and power factor G/|Y| against "
             "speed, measured and model (Lindsay and Barton Figs. 11-13).",
             _adm_drawer(curves, n_sync, err, "current"), size=(9.0, 6.5)),
        Plot("torque", "Torque against speed",
             ("Measured (points) and model (lines) electromagnetic torque against speed." if has_torque else
              "Model electromagnetic torque against speed (the data have no torque column)."),
             _adm_drawer(curves, n_sync, err, "torque")),
    ]


def _admittance_curves(problem, x: np.ndarray) -> list[dict]:
    """Per sweep table: the readings (speed, measured Y, voltage, torque) and the model on a fine
    grid through them. Between two readings slip, voltage and the temperature the fit assigned
    (copper factor, stator resistance rise) are interpolated in acquisition order, so the model
    line passes exactly through the model at every reading."""
    from benchmark.model.circuit import input_admittance, rotor_admittance, speed_from_slip

    d = problem.data
    c = problem.full_parameters(x[None, :])
    k_all = np.asarray(getattr(problem, "_k", np.ones(d.n)), float)
    dr_all = np.asarray(getattr(problem, "_dR1", np.zeros(d.n)), float)
    sweeps = d.sweep if d.sweep is not None else np.zeros(d.n, int)
    w_sync = 2 * np.pi * d.frequency / d.pole_pairs
    out = []
    for label in np.unique(sweeps):
        idx = np.flatnonzero(sweeps == label)
        m = 12 if len(idx) > 1 else 1
        u = np.linspace(0, len(idx) - 1, (len(idx) - 1) * m + 1)
        pos = np.arange(len(idx))

        def fine(v, idx=idx, u=u, pos=pos):
            return np.interp(u, pos, np.asarray(v, float)[idx])

        s, k, dr, V = fine(d.slip), fine(k_all), fine(dr_all), fine(d.voltage)
        R1t, R2 = c["R1_total"] + dr, c["R2"] * k
        with np.errstate(all="ignore"):
            Y = input_admittance(s, R1t, c["X1"], R2, c["X2"], c["R0"], c["X0"], c["R2sigma"], c["X3"])[0]
            Z0 = c["R0"] + 1j * c["X0"]
            Y2 = rotor_admittance(s, R2, c["X2"], c["R2sigma"], c["X3"])
            E = V * Y * (Z0 / (1.0 + Z0 * Y2))[0]
            I2 = E * Y2[0]
            T = 3.0 * np.real(E * np.conj(I2)) / w_sync
        Ym = d.Y[idx]
        out.append({
            "label": int(label), "speed": d.speed_rpm[idx], "Y": Ym, "V": d.voltage[idx],
            "T": None if d.torque is None else d.torque[idx],
            "model_speed": speed_from_slip(s, d.frequency, d.pole_pairs), "model_Y": Y, "model_V": V,
            "model_T": T,
        })
    return out


def _adm_drawer(curves: list[dict], n_sync: float, err: float, kind: str):
    many = len(curves) > 1

    def tag(cv) -> str:
        volts = np.unique(np.round(cv["V"], 3))
        v = f"{volts[0]:g} V" if len(volts) == 1 else f"{volts.min():g}-{volts.max():g} V"
        way = "up" if cv["speed"][-1] >= cv["speed"][0] else "down"
        return f"sweep {cv['label'] + 1}: {v}, {way}" if many else v

    def colors(j) -> tuple[str, str]:
        return (f"C{j % 10}", f"C{j % 10}") if many else (MEASURED, MODEL)

    def panel(ax, meas_fn, model_fn, ylabel):
        for j, cv in enumerate(curves):
            mc, lc = colors(j)
            mv = meas_fn(cv, False)
            if mv is not None:
                ax.plot(cv["speed"], mv, "o", ms=3.5, mfc="none", mec=mc, mew=0.9)
            ax.plot(cv["model_speed"], model_fn(cv, True), "-", color=lc, lw=1.3)
        ax.axvline(n_sync, color="0.5", ls=":", lw=1.0)
        ax.axhline(0.0, color="0.7", lw=0.6)
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)

    def legend(fig, measured: bool):
        """One legend beside the axes (it never hides a reading): the marker and line key, then
        one colour per sweep table when there are several."""
        from matplotlib.lines import Line2D

        v = "" if many else f" ({tag(curves[0])})"
        key = MEASURED if many else MODEL
        handles = ([Line2D([], [], ls="none", marker="o", ms=4, mfc="none", mec=MEASURED, label="measured" + v)]
                   if measured else [])
        handles.append(Line2D([], [], color=key, lw=1.3, label="model" + v))
        if many:
            handles += [Line2D([], [], color=f"C{j % 10}", marker="o", ms=4, mfc="none", lw=1.3, label=tag(cv))
                        for j, cv in enumerate(curves)]
        handles.append(Line2D([], [], color="0.5", ls=":", label=f"synchronous\nspeed ({n_sync:g} rpm)"))
        fig.legend(handles=handles, loc="outside right center", fontsize=8)

    def Ykey(cv, model):
        return cv["model_Y"] if model else cv["Y"]

    def Vkey(cv, model):
        return cv["model_V"] if model else cv["V"]

    def draw(fig):
        if kind == "admittance":
            a1, a2 = fig.subplots(2, 1, sharex=True)
            panel(a1, lambda cv, m: Ykey(cv, m).real, lambda cv, m: Ykey(cv, m).real, "conductance G (S)")
            panel(a2, lambda cv, m: Ykey(cv, m).imag, lambda cv, m: Ykey(cv, m).imag, "susceptance B (S)")
            a2.set_xlabel("speed (rpm)")
            fig.suptitle(f"Input admittance per phase against speed (RMS misfit {err:.3g} % of full scale; "
                         "Lindsay and Barton Figs. 11-13)", fontsize=10)
            legend(fig, True)
        elif kind == "current":
            a1, a2 = fig.subplots(2, 1, sharex=True)

            def current(cv, m):
                return Vkey(cv, m) * np.abs(Ykey(cv, m))

            def pf(cv, m):
                Y = Ykey(cv, m)
                return Y.real / np.abs(Y)

            panel(a1, current, current, "stator current (A RMS per phase)")
            panel(a2, pf, pf, "power factor cos(phi) (-)")
            a2.set_ylim(-1.05, 1.05)
            a2.set_xlabel("speed (rpm)")
            fig.suptitle("Stator current and power factor against speed (power factor < 0: generating; "
                         "Lindsay and Barton Figs. 11-13)", fontsize=10)
            legend(fig, True)
        else:
            ax = fig.subplots()
            has = any(cv["T"] is not None for cv in curves)
            panel(ax, lambda cv, m: cv["T"], lambda cv, m: cv["model_T"], "electromagnetic torque (N m)")
            ax.set_xlabel("speed (rpm)")
            ax.set_title("Torque against speed" + ("" if has else " (model only: the data have no torque column)"),
                         fontsize=10)
            legend(fig, has)
    return draw


# -- convergence -------------------------------------------------------------------------------
def convergence_plot(problem, record: dict, outdir: Path) -> Plot | None:
    path = outdir / str(record.get("history") or "history.csv")
    if not path.is_file():
        return None
    import pandas as pd

    h = pd.read_csv(path)
    if h.empty:
        return None
    total = int(record.get("evaluations") or h["evaluations"].max())

    phases = list(dict.fromkeys(h["phase"].astype(str)))
    n_opt = record.get("evaluations_optimizer")

    def draw(fig):
        ax = fig.subplots()
        cost = h["best_cost"].to_numpy(float)
        positive = bool(np.all(cost[np.isfinite(cost)] > 0))
        colors = {"optimizer": "C0", "polish": "C1"}
        last = None
        for k, phase in enumerate(phases):
            part = h[h["phase"].astype(str) == phase]
            e = part["evaluations"].to_numpy(float)
            c = part["best_cost"].to_numpy(float)
            if last is not None:  # the polish starts from the optimiser's best point
                e, c = np.concatenate([[last[0]], e]), np.concatenate([[last[1]], c])
            if k < len(phases) - 1:
                nxt = float(h["evaluations"][h["phase"].astype(str) == phases[k + 1]].iloc[0])
                end = float(n_opt) if phase == "optimizer" and n_opt else nxt - 1
            else:
                end = float(total)
            e, c = np.concatenate([e, [max(end, e[-1])]]), np.concatenate([c, [c[-1]]])
            name = record.get("optimizer", "optimizer") if phase == "optimizer" else phase
            ax.step(e, c, where="post", color=colors.get(phase, f"C{k + 2}"), lw=1.6,
                    label=f"{name}: {c[-1]:.4g} after {int(e[-1])} evaluations")
            last = (e[-1], c[-1])
        ax.set_xscale("log")
        ax.set_yscale("log" if positive else "symlog")
        ax.set_xlabel("evaluations (counted by the harness)")
        ax.set_ylabel(f"best cost so far\n({_cost_unit(problem)})", fontsize=9)
        ax.grid(True, which="major", alpha=0.3)
        ax.grid(True, which="minor", axis="x", alpha=0.1)
        ax.legend(fontsize=8, loc="lower left")
        ax.set_title(f"Convergence: {record.get('problem')} / {record.get('optimizer')}, seed {record.get('seed')} "
                     f"(budget {record.get('budget')})", fontsize=10)

    return Plot("convergence", "Convergence",
                "Best cost found against the evaluations counted by the harness (history.csv), log scales; "
                "the polish phase, when run, continues from the optimiser's best point.",
                draw, size=(8.0, 4.5))


def _cost_unit(problem) -> str:
    if getattr(problem, "name", "") == "timedomain":
        return ("eq. 15: weighted |error|, A and rad/s" if getattr(problem, "exponent", 1) == 1 else
                "eq. 14: weighted squared error")
    if getattr(problem, "name", "") == "admittance":
        return "S$^2$: mean squared G, B misfit, full scale = 1"
    return "the problem's cost"


# -- the run's figures and report --------------------------------------------------------------
#: Problem-specific figures by ``problem.name``; every problem also gets the convergence plot.
PROBLEM_PLOTS: dict[str, Callable] = {"timedomain": timedomain_plots, "admittance": admittance_plots}


def figure_plots(problem, record: dict, x: np.ndarray | None, outdir: Path) -> tuple[list[Plot], list[str]]:
    """The figures of this run (not yet drawn), and the errors met while preparing them."""
    plots, errors = [], []
    make = PROBLEM_PLOTS.get(getattr(problem, "name", ""))
    if make is not None:
        try:
            with np.errstate(all="ignore"):
                plots += make(problem, x, record)
        except Exception as exc:
            errors.append(f"{problem.name} figures: {type(exc).__name__}: {exc}")
    try:
        conv = convergence_plot(problem, record, Path(outdir))
        if conv is not None:
            plots.append(conv)
    except Exception as exc:
        errors.append(f"convergence: {type(exc).__name__}: {exc}")
    return plots, errors


def write_run_figures(problem, record: dict, x: np.ndarray | None, outdir) -> dict:
    """Draw and save every figure of the run into ``outdir`` and write ``report.md`` listing them.

    Returns ``{"report", "files", "errors", "time_s"}`` for ``result.json``. A figure that cannot
    be drawn is left out and its error listed; the others are still made."""
    from matplotlib.figure import Figure

    t0 = time.perf_counter()
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    plots, errors = figure_plots(problem, record, x, outdir)
    done = []
    for plot in plots:
        fig = Figure(figsize=plot.size, layout="constrained")
        try:
            with np.errstate(all="ignore"):
                plot.draw(fig)
                plot.files = _save(fig, outdir, plot.name)
            done.append(plot)
        except Exception as exc:
            errors.append(f"{plot.name}: {type(exc).__name__}: {exc}")
    write_report(outdir, record, done, errors)
    return {"report": REPORT_NAME, "files": [f for p in done for f in p.files], "errors": errors,
            "time_s": time.perf_counter() - t0}


def _command(argv: str) -> str:
    """The command as typed: ``.../benchmark/__main__.py ARGS`` -> ``python -m benchmark ARGS``."""
    head, _, rest = argv.partition(" ")
    path = Path(head)
    if path.name == "__main__.py" and path.parent.name:
        return f"python -m {path.parent.name} {rest}".rstrip()
    return argv


def write_report(outdir: Path, record: dict, plots: list[Plot], errors: list[str]) -> Path:
    """``report.md``: what was run, the estimate against the truth, warnings, and the figures."""
    from benchmark.data.tables import write_text_atomic

    r = record
    cost = r.get("cost")
    lines = [f"# {r.get('problem')} / {r.get('optimizer')}, seed {r.get('seed')}", ""]
    if r.get("command"):
        lines += [f"Command: `{_command(r['command'])}`", ""]
    info = r.get("problem_info") or {}
    if info.get("data"):
        lines += [f"Data: {info['data']}", ""]
    evals = f"{r.get('evaluations')} evaluations"
    pol = (r.get("polish") or {}).get("evaluations")
    if pol:
        evals += f" ({r.get('evaluations_optimizer')} by {r.get('optimizer')}, {pol} by polish)"
    lines += [f"Status **{r.get('status')}**: cost {'-' if cost is None else f'{cost:.6g}'} after {evals}, "
              f"budget {r.get('budget')}, {r.get('wall_time_s', 0):.2f} s."
              + (f" {r['message']}" if r.get("message") and r.get("status") != "budget_spent" else ""), ""]
    est, truth, err = r.get("estimate") or {}, r.get("truth") or {}, r.get("rel_error") or {}
    if est and truth:
        lines += ["| parameter | estimate | truth | error |", "|---|---|---|---|"]
        for k, v in est.items():
            t = f"{truth[k]:.6g}" if k in truth else "-"
            e = f"{100 * err[k]:+.3f} %" if k in err else "-"
            lines.append(f"| {k} | {v:.6g} | {t} | {e} |")
        lines.append("")
    elif est:  # measured data: no truth to score against
        lines += ["| parameter | estimate |", "|---|---|"] + [f"| {k} | {v:.6g} |" for k, v in est.items()] + [""]
    mech = info.get("mechanical")
    if mech:
        lines += [f"Free-stop pre-identification (case {mech['case']}): tau_m = {mech['tau_m']:.6g} s, "
                  f"fc/J = {mech['fc_over_J']:.6g} rad/s^2.", ""]
    warns = list(r.get("warnings") or []) + [f"figure not made: {e}" for e in errors]
    if warns:
        lines += ["Warnings:", ""] + [f"- {w}" for w in warns] + [""]
    lines += ["## Figures", ""]
    if not plots:
        lines += ["(none could be made)", ""]
    for p in plots:
        png = next((f for f in p.files if f.endswith(".png")), None)
        svg = next((f for f in p.files if f.endswith(".svg")), None)
        lines += [f"### {p.title}", "", f"![{p.title}]({png})", "", p.caption + (f" [SVG]({svg})" if svg else ""), ""]
    lines.append("Full record: [result.json](result.json); convergence history: [history.csv](history.csv).")
    path = Path(outdir) / REPORT_NAME
    write_text_atomic(path, "\n".join(lines) + "\n")
    return path

"""Figures of an admittance run: conductance and susceptance against speed, stator current and
power factor against speed (Lindsay and Barton Figs. 11-13), and torque against speed
(measured and model when the data have a torque column, else the model alone). Drawn by
:func:`benchmark.core.plotting.write_run_figures` through :meth:`AdmittanceProblem.plots`."""

from __future__ import annotations

import numpy as np

from benchmark.core.plotting import MEASURED, MODEL, Plot


# -- admittance --------------------------------------------------------------------------------
def admittance_plots(problem, x: np.ndarray | None, record: dict) -> list[Plot]:
    if x is None:
        return []
    if problem.data.test is not None:  # a test report: per test, not against one speed axis
        from benchmark.problems.admittance.loadtest_figures import loadtest_plots

        return loadtest_plots(problem, x, record)
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
    from benchmark.problems.admittance.circuit import input_admittance, rotor_admittance, speed_from_slip

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



"""The figure of a run on a motor test report (``kind: loadtest``): per test, the measured and the
model's stator current and power factor at every reading (the model at each reading's slip,
frequency, temperature and flux: :meth:`AdmittanceProblem.admittance`), against speed for the load
points and against voltage for the no-load and locked-rotor tests."""

from __future__ import annotations

import numpy as np

from benchmark.core.plotting import MEASURED, MODEL, Plot

#: Test label -> (title, x quantity).
PANELS = {"load": ("load points", "speed"), "noload": ("no-load test", "voltage"),
          "locked": ("locked-rotor test", "voltage")}


def loadtest_plots(problem, x, record: dict) -> list[Plot]:
    if x is None:
        return []
    d = problem.data
    Y_model = problem.admittance(np.asarray(x, float))[0]
    tests = [t for t in PANELS if np.any(d.test == t)]

    def draw(fig):
        axes = fig.subplots(2, len(tests), squeeze=False)
        for j, t in enumerate(tests):
            m = d.test == t
            title, xq = PANELS[t]
            xs = d.speed_rpm[m] if xq == "speed" else d.voltage[m]
            order = np.argsort(xs)
            for i, (label, f) in enumerate((("stator current (A per phase)", lambda Y, V: V * np.abs(Y)),
                                            ("power factor", lambda Y, V: Y.real / np.abs(Y)))):
                ax = axes[i, j]
                ax.plot(xs[order], f(d.Y[m], d.voltage[m])[order], "o", ms=4, mfc="none", mec=MEASURED,
                        label="measured")
                ax.plot(xs[order], f(Y_model[m], d.voltage[m])[order], "-", color=MODEL, lw=1.3, marker=".",
                        label="model")
                ax.grid(alpha=0.3)
                if j == 0:
                    ax.set_ylabel(label)
                if i == 0:
                    ax.set_title(title, fontsize=10)
                else:
                    ax.set_xlabel("speed (rpm)" if xq == "speed" else "voltage (V per phase)")
        axes[0, 0].legend(fontsize=8)
        fig.suptitle("Test report: measured and model at every reading (per phase of the winding as connected)",
                     fontsize=10)

    return [Plot("loadtest", "Test report: measured and model",
                 "Stator current and power factor per test, measured (points) and model (line through its value "
                 "at each reading: the reading's slip, frequency, temperature and flux).", draw,
                 size=(4.0 * len(tests) + 1.5, 6.5))]

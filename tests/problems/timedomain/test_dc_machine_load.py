"""A load that follows a DC machine's armature circuit (``load_torque``'s switched part).

A real bench's DC generator, switched onto its resistor for half a second of a two-second
record, fitted none of the constant, quadratic or step forms (verdict ``unexplained``): its
torque ``k^2 w / R`` follows the speed and rises with the armature's time constant ``L_a/R``.
The augmentation's switched part has a first-order rise, a switch-off and a share that follows
speed; the own plant's ``dc_machine`` form draws such loads."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import optimize

from benchmark.core.effects import effect_context, load_effects
from benchmark.problems.timedomain.diagnosis.free_coast import switched_at_end
from benchmark.problems.timedomain.extended import IDX, base_row, simulate_extended_batch
from benchmark.problems.timedomain.extended_mechanics import _switched
from benchmark.problems.timedomain.protocol import StartupStopTest
from tests.conftest import PAPER_MOTOR

LOAD = load_effects("timedomain", ["load_torque"])["load_torque"]
FORM = {"kind": "dc_machine", "step_fraction": 0.45, "tau": 0.03, "off_fraction": 0.8}


def _record(cycles=40):
    t, va, vb = StartupStopTest(cycles=cycles).startup_voltages()
    base = base_row(PAPER_MOTOR)
    ref = simulate_extended_batch(np.ascontiguousarray(base[None]), va, vb, False, 1 / 12000, 1)[0]
    ctx = effect_context(t, va, vb, ref[0], ref[1], ref[2], 1, PAPER_MOTOR.J, PAPER_MOTOR.Ls - PAPER_MOTOR.Le,
                         PAPER_MOTOR.Le, 300.0)
    return base, va, vb, ctx


def test_the_switched_envelope_rises_first_order_and_falls_after_its_switch_off():
    tau, on, off = 0.03, 0.2, 0.5
    assert _switched(0.19, on, 0.0, tau, off) == 0.0
    assert _switched(on + tau, on, 0.0, tau, off) == pytest.approx(1 - np.exp(-1.0), rel=1e-12)
    at_off = 1 - np.exp(-(off - on) / tau)
    assert _switched(off + 2 * tau, on, 0.0, tau, off) == pytest.approx(at_off * np.exp(-2.0), rel=1e-12)
    assert _switched(0.9, on, 0.0, tau, 0.1) == pytest.approx(1 - np.exp(-0.7 / tau))  # off before on: never
    assert _switched(on, on, 0.0, 0.0, off) == 1.0 and _switched(on - 1e-9, on, 0.0, 0.0, off) == 0.0
    col = {"t_step": np.array([[on], [on], [on], [0.9]]), "tau_s": np.array([[tau], [tau], [0.0], [tau]]),
           "t_step_off": np.array([[off], [0.0], [0.0], [0.0]])}
    end = switched_at_end(col, 0.6)  # the free stop starts from the envelope at the start-up's end
    np.testing.assert_allclose(end[:, 0], [_switched(0.6, on, 0.0, tau, off), _switched(0.6, on, 0.0, tau, 0.0),
                                           1.0, 0.0], rtol=1e-12)


def test_the_dc_machine_form_is_the_augmentation_at_its_parameters():
    base, va, vb, ctx = _record(20)
    size = 0.4
    plant = LOAD.plant(base, size, ctx, FORM)
    extras = np.array([[0.0, 0.0, size, FORM["step_fraction"], 1.0, FORM["tau"], FORM["off_fraction"]]])
    model = LOAD.augment(base[None], extras, ctx)[0]
    for name in ("T_s", "t_step", "T_s_speed", "tau_s", "t_step_off", "w_ref"):
        assert model[IDX[name]] == pytest.approx(plant[IDX[name]], rel=1e-12), name
    out = simulate_extended_batch(np.ascontiguousarray(np.stack([plant, model])), va, vb, False, 1 / 12000, 1)
    ref = simulate_extended_batch(np.ascontiguousarray(base[None]), va, vb, False, 1 / 12000, 1)[0]
    np.testing.assert_allclose(out[1], out[0], rtol=0, atol=1e-9 * np.abs(out[0]).max())
    n = out.shape[2]
    # a generator's torque follows speed: the speed sags after the switch-on and recovers after the switch-off
    on, off = int(FORM["step_fraction"] * n), int(FORM["off_fraction"] * n)
    sag = ref[2] - out[0, 2]
    assert abs(sag[on - 5]) < 1e-9 and sag[off - 1] > 0.5 and sag[-1] < 0.5 * sag[off - 1]


def test_the_augmentation_finds_a_switched_dc_machine_from_its_starts():
    """From the starts the current envelope gives (its rise after the switch-on, its fall at the
    switch-off), the switch-on moved to the best of its grid as the selection does
    (``Selector.profiled``), a local fit of the load's extras recovers a DC generator's torque,
    instants and armature time constant."""
    base, va, vb, ctx = _record(40)
    plant = LOAD.plant(base, 0.4, ctx, FORM)
    meas = simulate_extended_batch(np.ascontiguousarray(plant[None]), va, vb, False, 1 / 12000, 1)[0]
    t = np.arange(meas.shape[1]) / 12000
    ctx = effect_context(t, va, vb, meas[0], meas[1], meas[2], 1, PAPER_MOTOR.J, PAPER_MOTOR.Ls - PAPER_MOTOR.Le,
                         PAPER_MOTOR.Le, 300.0)  # the context of the loaded record, as the diagnosis makes it
    on, off = FORM["step_fraction"] * ctx.duration, FORM["off_fraction"] * ctx.duration
    assert on < ctx.load_change < on + 0.1  # the envelope's largest rise lags while the rotor slows
    assert off < ctx.load_release < off + 0.1  # and its fall, with the armature and the speed
    lo, hi = LOAD.extra_bounds(ctx)
    scale = np.array([0.05, 0.05, 0.25])[:, None]  # noise-like units: A, A, rad/s

    def res(U):  # residual rows of unit-box extras U (n, 7), simulated in one batch
        X = lo + np.atleast_2d(U) * (hi - lo)
        sim = simulate_extended_batch(np.ascontiguousarray(LOAD.augment(np.tile(base, (len(X), 1)), X, ctx)),
                                      va, vb, False, 1 / 12000, 1)
        return ((sim - meas[None]) / scale).reshape(len(X), -1)

    def jac(u):
        h = np.where(u < 0.5, 1e-6, -1e-6)
        R = res(np.vstack([u, u + np.diag(h)]))
        return ((R[1:] - R[0]) / h[:, None]).T

    col, grid = LOAD.start_grid(ctx)
    best = None
    for s in LOAD.extra_starts(ctx):
        if s[4] < 1.0:  # the DC machine's starts (the steps' are the step form's)
            continue
        U = np.tile((s - lo) / (hi - lo), (len(grid), 1))
        U[:, col] = (grid - lo[col]) / (hi[col] - lo[col])
        u0 = U[int(np.argmin(np.sum(res(U) ** 2, axis=1)))]
        sol = optimize.least_squares(lambda u: res(u)[0], u0, jac=jac, bounds=(0, 1), max_nfev=60, x_scale="jac")
        if best is None or sol.cost < best.cost:
            best = sol
    x = lo + best.x * (hi - lo)
    assert np.sqrt(np.mean(best.fun**2)) < 0.05  # a twentieth of the noise: the form is the plant's
    assert x[2] * (1 - x[4]) + x[0] < 0.02 and x[2] * x[4] == pytest.approx(0.4, rel=0.02)  # it follows speed
    assert x[3] == pytest.approx(FORM["step_fraction"], abs=0.002) and x[6] == pytest.approx(FORM["off_fraction"],
                                                                                             abs=0.002)
    assert x[5] == pytest.approx(FORM["tau"], rel=0.05)

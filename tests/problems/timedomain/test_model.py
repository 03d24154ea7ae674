"""The compiled motor model against independent expectations: an adaptive scipy solve_ivp
integration of the same equations, the paper's reported transients, and physical invariants."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from benchmark.problems.timedomain.frames import clarke, inverse_clarke
from benchmark.problems.timedomain.motor import InductionMotor, coefficients
from benchmark.problems.timedomain.protocol import StartupStopTest, phase_voltages, run_startup_stop
from benchmark.problems.timedomain.simulation import simulate_states, startup_cost_batch, startup_outputs_batch


def reference_rhs(motor: InductionMotor, v_of_t):
    """the model written out directly (no shared code with the compiled model)."""
    Rs, Ls, Le, Rr, J, fv, p = motor.Rs, motor.Ls, motor.Le, motor.Rr, motor.J, motor.fv, motor.p
    Lr = Ls
    Lm = math.sqrt(Lr * (Ls - Le))

    def rhs(t, x):
        i_a, i_b, psi_a, psi_b, w = x
        v_a, v_b = v_of_t(t)
        Re = Rs + (Lm / Lr) ** 2 * Rr
        di_a = -Re / Le * i_a + Rr / Lr * Lm / (Le * Lr) * psi_a + Lm / (Le * Lr) * w * psi_b + v_a / Le
        di_b = -Re / Le * i_b + Rr / Lr * Lm / (Le * Lr) * psi_b - Lm / (Le * Lr) * w * psi_a + v_b / Le
        dpsi_a = Rr * Lm / Lr * i_a - Rr / Lr * psi_a - w * psi_b
        dpsi_b = Rr * Lm / Lr * i_b - Rr / Lr * psi_b + w * psi_a
        t_m = 1.5 * p * Lm / Lr * (psi_a * i_b - psi_b * i_a)
        dw = -w * fv / J + p / J * t_m
        return [di_a, di_b, dpsi_a, dpsi_b, dw]

    return rhs


def test_clarke_round_trip_and_amplitude():
    t = np.linspace(0, 0.04, 101)
    amp = 7.3
    r, s, tt = (amp * np.cos(2 * np.pi * 50 * t - k * 2 * np.pi / 3) for k in range(3))
    a, b = clarke(r, s, tt)
    np.testing.assert_allclose(np.hypot(a, b), amp, rtol=1e-12)  # amplitude-invariant
    r2, s2, t2 = inverse_clarke(a, b)
    np.testing.assert_allclose([r2, s2, t2], [r, s, tt], atol=1e-12)


def test_six_step_vector_length_is_two_thirds_of_dc_link():
    v = phase_voltages(np.array([[1, 0, 0], [1, 1, 0], [0, 1, 1], [1, 1, 1]]), 300.0)
    np.testing.assert_allclose(v.sum(axis=1), 0.0, atol=1e-12)
    a, b = clarke(v[:, 0], v[:, 1], v[:, 2])
    np.testing.assert_allclose(np.hypot(a, b), [200.0, 200.0, 200.0, 0.0], atol=1e-12)


@pytest.mark.parametrize("waveform", ["sinusoidal", "six_step"])
def test_rk4_matches_adaptive_reference(paper_motor, waveform):
    """No Coulomb friction (smooth dynamics): RK4 at 12 kHz vs solve_ivp at rtol 1e-10 over 0.3 s."""
    motor = InductionMotor(**{**paper_motor.as_dict(), "fc": 0.0})
    test = StartupStopTest(cycles=15, waveform=waveform)
    t, v_a, v_b = test.startup_voltages()
    ts = test.sample_time
    if waveform == "sinusoidal":
        amp = 2 * 300 / math.pi
        w_e = 2 * math.pi * test.supply_frequency

        def v_of_t(tau):
            return amp * math.cos(w_e * tau), amp * math.sin(w_e * tau)
        ref = solve_ivp(reference_rhs(motor, v_of_t), (0, t[-1]), np.zeros(5), t_eval=t, rtol=1e-10, atol=1e-10,
                        method="DOP853").y
    else:
        # piecewise-constant input: integrate each held interval separately
        x = np.zeros(5)
        ref = np.empty((5, len(t)))
        ref[:, 0] = x
        for k in range(len(t) - 1):
            va, vb = v_a[k], v_b[k]
            sol = solve_ivp(reference_rhs(motor, lambda tau, va=va, vb=vb: (va, vb)), (0, ts), x, rtol=1e-10,
                            atol=1e-10, method="DOP853")
            x = sol.y[:, -1]
            ref[:, k + 1] = x
    c = coefficients(motor.vector()[None], 1)[0]
    x = simulate_states(c, v_a, v_b, waveform == "sinusoidal", ts, 1, np.zeros(5))
    i_peak = np.max(np.abs(ref[0]))
    assert np.max(np.abs(x[:, 0] - ref[0])) < 2e-4 * i_peak
    assert np.max(np.abs(x[:, 1] - ref[1])) < 2e-4 * i_peak
    assert np.max(np.abs(x[:, 4] - ref[4])) < 2e-4 * np.max(np.abs(ref[4]))


def test_paper_transients(paper_records):
    """the start-up/stop experiment: start-up current peaks near 28 A; stop from ~314 to ~266 rad/s in 0.1 s."""
    s, st = paper_records["startup"], paper_records["stop"]
    peak = np.max(np.hypot(s["i_alpha"], s["i_beta"]))
    assert 26.0 < peak < 30.0
    assert 312.0 < s["speed"][-1] < 314.2  # just below the 100*pi synchronous speed
    assert 264.0 < np.interp(0.1, st["t"], st["speed"]) < 268.0
    # coasts to rest in about tau*ln(1 + w0/(tau fc/J)) ~ 21.7 s, then stays there (stiction)
    rest = st["t"][np.argmax(st["speed"] <= 0)]
    assert 21.0 < rest < 22.5
    assert np.all(st["speed"][st["t"] > rest] == 0.0)


def test_zero_input_from_rest_stays_at_rest(paper_motor):
    c = coefficients(paper_motor.vector()[None], 1)[0]
    z = np.zeros(2000)
    x = simulate_states(c, z, z, False, 1 / 12000, 1, np.zeros(5))
    assert np.all(x == 0.0)


def test_stiction_holds_rotor_against_small_torque(paper_motor):
    """With Coulomb friction above the largest start-up torque the rotor never moves."""
    strong = InductionMotor(**{**paper_motor.as_dict(), "fc": 50.0})
    rec = run_startup_stop(strong, StartupStopTest(cycles=5), substeps=1)
    assert np.all(rec["startup"]["speed"] == 0.0)
    assert np.max(np.abs(rec["startup"]["i_alpha"])) > 10.0


def test_batch_cost_matches_outputs_and_flags_bad_candidates(paper_motor, paper_records):
    s = paper_records["startup"]
    theta = np.stack([paper_motor.vector(), paper_motor.vector() * 1.01,
                      paper_motor.vector() * np.array([1, 1, 20, 1, 1, 1, 1]),  # Le > Ls: non-physical
                      paper_motor.vector() * np.array([1, 1, 1e-6, 1, 1, 1, 1])])  # absurd: tiny Le
    coef = coefficients(theta, 1)
    args = (s["v_alpha"], s["v_beta"], False, 1 / 12000)
    w = np.array([1.0, 2.0, 0.5])
    cost2 = startup_cost_batch(coef, *args, s["i_alpha"], s["i_beta"], s["speed"], 1.0, w, 2)
    out = startup_outputs_batch(coef, *args, 1.0)
    for k in range(2):
        e = np.stack([s["i_alpha"], s["i_beta"], s["speed"]]) - out[k]
        expected = float(np.sum(w[:, None] * e**2))
        assert cost2[k] == pytest.approx(expected, rel=1e-10)
    assert cost2[2] == np.inf
    assert np.isfinite(cost2[3]) or cost2[3] == np.inf  # never NaN
    assert not np.isnan(cost2).any()

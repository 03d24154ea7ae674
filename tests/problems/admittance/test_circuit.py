"""Physics of the steady-state equivalent circuit (benchmark.problems.admittance.circuit).

Expectations are computed here independently (textbook circuit algebra, the paper's figures), not
by calling the function under test a second time.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from benchmark.problems.admittance.circuit import (
    CircuitParameters,
    ThermalModel,
    bilinear_coefficients,
    bilinear_to_circuit,
    copper_factor,
    input_admittance,
    operating_point,
    slip_from_speed,
    temperature_from_resistance,
    warped_slip,
)

# Lindsay and Barton's 8-parameter model F (ohm at 60 Hz, 50 C)
MODEL_F = CircuitParameters(
    R1=0.2045,
    R1sigma=0.0061,
    X1=0.5580,
    R2=0.2941,
    R2sigma=0.0340,
    X2=0.5579,
    X3=0.0093,
    R0=1.0592,
    X0=16.0998,
)
# their 6-parameter model D
MODEL_D = CircuitParameters(R1=0.2337, X1=0.5521, R2=0.2983, X2=0.5530, R0=1.051, X0=16.11)
F_HZ, P = 60.0, 2
V = 30.2


def textbook_admittance(p: CircuitParameters, s: float) -> complex:
    """Direct series-parallel reduction with the rotor impedance R2/s + ... (s != 0)."""
    Z1 = complex(p.R1 + p.R1sigma, p.X1)
    Z0 = complex(p.R0, p.X0)
    Z2 = complex(p.R2 / s + p.R2sigma * np.sign(s), p.X2 - p.X3 * abs(s))
    return 1.0 / (Z1 + Z0 * Z2 / (Z0 + Z2))


def test_admittance_matches_textbook_reduction_and_synchronous_limit():
    for s in (2.0, 1.0, 0.3, 0.02, -0.05, -1 / 3):
        y = input_admittance(
            s,
            MODEL_F.R1_total,
            MODEL_F.X1,
            MODEL_F.R2,
            MODEL_F.X2,
            MODEL_F.R0,
            MODEL_F.X0,
            MODEL_F.R2sigma,
            MODEL_F.X3,
        )
        assert y == pytest.approx(textbook_admittance(MODEL_F, s), rel=1e-13)
    # at s = 0 the rotor is open: Y = 1/(Z1 + Z0)
    y0 = input_admittance(
        0.0,
        MODEL_F.R1_total,
        MODEL_F.X1,
        MODEL_F.R2,
        MODEL_F.X2,
        MODEL_F.R0,
        MODEL_F.X0,
        MODEL_F.R2sigma,
        MODEL_F.X3,
    )
    assert y0 == pytest.approx(1 / complex(0.2106 + 1.0592, 0.5580 + 16.0998), rel=1e-13)
    # lagging machine: B < 0 everywhere
    s = np.linspace(-1 / 3, 2, 200)
    assert np.all(input_admittance(s, 0.2106, 0.558, 0.2941, 0.5579, 1.0592, 16.0998, 0.034, 0.0093).imag < 0)


def test_slip_of_the_paper_sweep():
    s = slip_from_speed(np.array([-1800.0, 0.0, 1800.0, 2400.0]), F_HZ, P)
    np.testing.assert_allclose(s, [2.0, 1.0, 0.0, -1 / 3], atol=1e-15)


def test_torque_signs_motoring_generating_braking():
    op = operating_point(MODEL_F, np.array([0.04, 0.5, -0.1, -1 / 3, 1.5, 2.0]), V, F_HZ, P)
    mot, gen, brk = slice(0, 2), slice(2, 4), slice(4, 6)
    assert np.all(op.torque[mot] > 0) and np.all(op.P_mech[mot] > 0) and np.all(op.P_ag[mot] > 0)
    # generating: shaft drives, power flows back across the air gap
    assert np.all(op.torque[gen] < 0) and np.all(op.P_ag[gen] < 0) and np.all(op.P_mech[gen] < 0)
    # braking: torque opposes the (reversed) rotation, shaft power is absorbed, the rotor
    # dissipates both the air-gap power and the shaft power
    assert np.all(op.torque[brk] > 0) and np.all(op.P_mech[brk] < 0)
    assert np.all(op.P_rotor[brk] > op.P_ag[brk]) and np.all(op.P_in[brk] > 0)
    # zero torque exactly at synchronous speed
    assert operating_point(MODEL_F, 0.0, V, F_HZ, P).torque == 0.0


def test_torque_equals_rotor_current_times_effective_resistance():
    s = np.array([1.0, 0.3, -0.2, 2.0])
    op = operating_point(MODEL_F, s, V, F_HZ, P)
    w_sync = 2 * np.pi * F_HZ / P  # 188.5 rad/s for 4 poles, 60 Hz
    for k, sk in enumerate(s):
        Z0 = complex(MODEL_F.R0, MODEL_F.X0)
        Z2 = complex(MODEL_F.R2 / sk + MODEL_F.R2sigma * np.sign(sk), MODEL_F.X2 - MODEL_F.X3 * abs(sk))
        I1 = V * textbook_admittance(MODEL_F, sk)
        I2 = I1 * Z0 / (Z0 + Z2)
        T = 3 * abs(I2) ** 2 * Z2.real / w_sync
        assert op.torque[k] == pytest.approx(T, rel=1e-12)


params_strategy = st.builds(
    CircuitParameters,
    R1=st.floats(0.05, 2.0),
    X1=st.floats(0.1, 3.0),
    R2=st.floats(0.05, 2.0),
    X2=st.floats(0.1, 3.0),
    R0=st.floats(0.0, 5.0),
    X0=st.floats(5.0, 60.0),
    R1sigma=st.floats(0.0, 0.05),
    R2sigma=st.floats(0.0, 0.1),
    X3=st.floats(0.0, 0.05),
)


@settings(max_examples=60, deadline=None)
@given(params_strategy, st.floats(-1.0, 3.0), st.floats(10.0, 400.0))
def test_power_balance(p, s, v):
    """Input power = stator losses + core loss + rotor losses + mechanical power, and = 3 V^2 G."""
    op = operating_point(p, s, v, F_HZ, P)
    parts = op.P_stator + op.P_core + op.P_rotor + op.P_mech
    assert op.P_in == pytest.approx(parts, rel=1e-9, abs=1e-9 * v**2)
    assert op.P_in == pytest.approx(3 * v**2 * op.Y.real, rel=1e-12, abs=1e-12)
    # rotor losses: copper R2 |I2|^2 plus the leakage core loss R2sigma*|s|*|I2|^2
    assert op.P_rotor == pytest.approx(3 * abs(op.I2) ** 2 * (p.R2 + p.R2sigma * abs(s)), rel=1e-9, abs=1e-12)


def circle_through(z1, z2, z3):
    """Centre and radius of the circle through three complex points."""
    ax, ay, bx, by, cx, cy = z1.real, z1.imag, z2.real, z2.imag, z3.real, z3.imag
    d = 2 * (ax * (by - cy) + bx * (cy - ay) + cx * (ay - by))
    ux = ((ax**2 + ay**2) * (by - cy) + (bx**2 + by**2) * (cy - ay) + (cx**2 + cy**2) * (ay - by)) / d
    uy = ((ax**2 + ay**2) * (cx - bx) + (bx**2 + by**2) * (ax - cx) + (cx**2 + cy**2) * (bx - ax)) / d
    c = complex(ux, uy)
    return c, abs(z1 - c)


@settings(max_examples=40, deadline=None)
@given(params_strategy)
def test_six_parameter_admittance_locus_is_a_circle(p):
    p6 = CircuitParameters(R1=p.R1, X1=p.X1, R2=p.R2, X2=p.X2, R0=p.R0, X0=p.X0)
    s = np.linspace(-1 / 3, 2, 43)
    Y = input_admittance(s, p6.R1_total, p6.X1, p6.R2, p6.X2, p6.R0, p6.X0)
    c, r = circle_through(Y[0], Y[20], Y[-1])
    np.testing.assert_allclose(np.abs(Y - c), r, rtol=1e-8)
    # and it is the bilinear form with the documented coefficients
    A, B, C, a, b, cc = bilinear_coefficients(p6.R1_total, p6.X1, p6.R2, p6.X2, p6.R0, p6.X0)
    np.testing.assert_allclose(Y, (a + b * s) / (1 + cc * s), rtol=1e-12)
    np.testing.assert_allclose(1 / Y, (A + B * s) / (1 + C * s), rtol=1e-12)


def test_eight_parameter_circuit_leaves_the_circle_but_is_bilinear_in_the_warped_slip():
    s = np.linspace(-1 / 3, 2, 43)
    p = MODEL_F
    Y = input_admittance(s, p.R1_total, p.X1, p.R2, p.X2, p.R0, p.X0, p.R2sigma, p.X3)
    c, r = circle_through(Y[0], Y[20], Y[-1])
    assert np.max(np.abs(np.abs(Y - c) - r)) > 1e-3 * r  # R2sigma*sign(s) and X3|s| bend the locus
    sw = warped_slip(s, p.R2, p.R2sigma, p.X3)
    _, _, _, a, b, cc = bilinear_coefficients(p.R1_total, p.X1, p.R2, p.X2, p.R0, p.X0)
    np.testing.assert_allclose(Y, (a + b * sw) / (1 + cc * sw), rtol=1e-12)


def test_bilinear_mapping_back_recovers_the_circuit():
    _, _, _, a, b, c = bilinear_coefficients(
        MODEL_D.R1_total, MODEL_D.X1, MODEL_D.R2, MODEL_D.X2, MODEL_D.R0, MODEL_D.X0
    )
    free = bilinear_to_circuit(a, b, c)
    for k, v in {"R1t": 0.2337, "X1": 0.5521, "R2": 0.2983, "X2": 0.5530, "R0": 1.051, "X0": 16.11}.items():
        assert free[k] == pytest.approx(v, rel=1e-10)
    # the tied mapping is exact when X1 = X2
    _, _, _, a, b, c = bilinear_coefficients(0.2337, 0.55, 0.2983, 0.55, 1.051, 16.11)
    tied = bilinear_to_circuit(a, b, c, tie_x1_x2=True)
    for k, v in {"R1t": 0.2337, "X1": 0.55, "R2": 0.2983, "X2": 0.55, "R0": 1.051, "X0": 16.11}.items():
        assert tied[k] == pytest.approx(v, rel=1e-10)


def test_copper_temperature_law_and_the_papers_five_degree_figures():
    assert copper_factor(55.0, 50.0) == pytest.approx((234.5 + 55) / (234.5 + 50))
    R_warm = 0.2045 * copper_factor(55.0, 50.0)
    assert temperature_from_resistance(R_warm, 0.2045, 50.0) == pytest.approx(55.0)
    # the paper: for its machine a 5 C rise raises the stalled torque by 1 % and the input
    # conductance by 1.25 %; model F reproduces both within a quarter of a percentage point
    s = np.array([1.0, 2.0])
    cold = operating_point(MODEL_F, s, V, F_HZ, P)
    warm = operating_point(MODEL_F.at_temperature(55.0, 50.0), s, V, F_HZ, P)
    dT = 100 * (warm.torque[0] / cold.torque[0] - 1)
    dG = 100 * (warm.Y.real / cold.Y.real - 1)
    assert 0.75 < dT < 1.25
    assert 1.0 < dG[1] < 1.5 and 0.75 < dG[0] < 1.25


def test_thermal_step_is_the_exact_solution():
    th = ThermalModel(
        capacitance=11300.0,
        conductance_standstill=8.0,
        conductance_at_speed=20.0,
        conductance_speed_rpm=1800.0,
        ambient_temperature=25.0,
    )
    assert th.conductance(900.0) == pytest.approx(14.0)
    assert th.conductance(-1800.0) == pytest.approx(20.0)
    P_w, n, dt = 800.0, 600.0, 30.0
    # fine explicit Euler as the independent reference
    theta, h = 50.0, 1e-3
    for _ in range(int(dt / h)):
        theta += h * (P_w - th.conductance(n) * (theta - 25.0)) / 11300.0
    assert th.step(50.0, P_w, n, dt) == pytest.approx(theta, abs=1e-5)
    # adiabatic limit
    adiabatic = ThermalModel(11300.0, 0.0, 0.0, 1800.0, 25.0)
    assert adiabatic.step(50.0, P_w, n, dt) == pytest.approx(50.0 + P_w * dt / 11300.0)

"""The chunked SIMD population kernel (benchmark.problems.timedomain.simulation) against the previous
one-candidate-per-thread kernel, kept here verbatim as the reference: equal bit for bit, and
independent of thread count, chunk width, block split, population order and company."""

from __future__ import annotations

import numba
import numpy as np
import pytest

from benchmark.problems.timedomain.motor import coefficients, state_derivative
from benchmark.problems.timedomain.protocol import StartupStopTest
from benchmark.problems.timedomain.simulation import (
    DIVERGENCE_LIMIT,
    LANES,
    _cost_batch,
    _outputs_batch,
    simulate_states,
    startup_cost_batch,
    startup_outputs_batch,
)
from tests.conftest import PAPER_MOTOR


# -- the previous implementation (commit 72caf14), serial, as the reference ---------------------
@numba.njit(cache=True)
def _ref_rk4(c, i_a, i_b, psi_a, psi_b, w, va0, vb0, vam, vbm, va1, vb1, h):
    d = 1.0 if w > 0.0 else (-1.0 if w < 0.0 else 0.0)
    k1 = state_derivative(c, i_a, i_b, psi_a, psi_b, w, va0, vb0, d)
    hh = 0.5 * h
    k2 = state_derivative(
        c, i_a + hh * k1[0], i_b + hh * k1[1], psi_a + hh * k1[2], psi_b + hh * k1[3],
        w + hh * k1[4], vam, vbm, d,
    )
    k3 = state_derivative(
        c, i_a + hh * k2[0], i_b + hh * k2[1], psi_a + hh * k2[2], psi_b + hh * k2[3],
        w + hh * k2[4], vam, vbm, d,
    )
    k4 = state_derivative(
        c, i_a + h * k3[0], i_b + h * k3[1], psi_a + h * k3[2], psi_b + h * k3[3],
        w + h * k3[4], va1, vb1, d,
    )
    h6 = h / 6.0
    n_ia = i_a + h6 * (k1[0] + 2.0 * (k2[0] + k3[0]) + k4[0])
    n_ib = i_b + h6 * (k1[1] + 2.0 * (k2[1] + k3[1]) + k4[1])
    n_pa = psi_a + h6 * (k1[2] + 2.0 * (k2[2] + k3[2]) + k4[2])
    n_pb = psi_b + h6 * (k1[3] + 2.0 * (k2[3] + k3[3]) + k4[3])
    n_w = w + h6 * (k1[4] + 2.0 * (k2[4] + k3[4]) + k4[4])
    fc = c[9]
    if fc > 0.0 and w != 0.0 and n_w * w <= 0.0:
        t_m = c[6] * (n_pa * n_ib - n_pb * n_ia)
        if abs(t_m) <= fc:
            n_w = 0.0
    return n_ia, n_ib, n_pa, n_pb, n_w


@numba.njit(cache=True)
def _ref_stage_voltages(v_a, v_b, k, linear):
    va0, vb0 = v_a[k], v_b[k]
    if linear:
        va1, vb1 = v_a[k + 1], v_b[k + 1]
        return va0, vb0, 0.5 * (va0 + va1), 0.5 * (vb0 + vb1), va1, vb1
    return va0, vb0, va0, vb0, va0, vb0


@numba.njit(cache=True)
def _ref_diverged(i_a, i_b, psi_a, psi_b, w):
    m = max(abs(i_a), abs(i_b), abs(psi_a), abs(psi_b), abs(w))
    return not (m < DIVERGENCE_LIMIT)


@numba.njit(cache=True)
def ref_cost_batch(coef, v_a, v_b, linear, h, i_a_meas, i_b_meas, speed_meas, p, weights, exponent):
    n_pop = coef.shape[0]
    n = v_a.shape[0]
    ka, kb, kw = weights[0], weights[1], weights[2]
    inv_p = 1.0 / p
    out = np.empty(n_pop)
    for m in range(n_pop):
        c = coef[m]
        if not np.isfinite(c[0]):
            out[m] = np.inf
            continue
        i_a = 0.0
        i_b = 0.0
        psi_a = 0.0
        psi_b = 0.0
        w = 0.0
        total = 0.0
        for k in range(n):
            ea = i_a_meas[k] - i_a
            eb = i_b_meas[k] - i_b
            ew = speed_meas[k] - w * inv_p
            if exponent == 2:
                total += ka * ea * ea + kb * eb * eb + kw * ew * ew
            else:
                total += ka * abs(ea) + kb * abs(eb) + kw * abs(ew)
            if k == n - 1:
                break
            va0, vb0, vam, vbm, va1, vb1 = _ref_stage_voltages(v_a, v_b, k, linear)
            i_a, i_b, psi_a, psi_b, w = _ref_rk4(c, i_a, i_b, psi_a, psi_b, w,
                                                 va0, vb0, vam, vbm, va1, vb1, h)
            if _ref_diverged(i_a, i_b, psi_a, psi_b, w):
                total = np.inf
                break
        out[m] = total if np.isfinite(total) else np.inf
    return out


@numba.njit(cache=True)
def ref_outputs_batch(coef, v_a, v_b, linear, h, p):
    n_pop = coef.shape[0]
    n = v_a.shape[0]
    out = np.full((n_pop, 3, n), np.nan)
    inv_p = 1.0 / p
    for m in range(n_pop):
        c = coef[m]
        if not np.isfinite(c[0]):
            continue
        i_a = 0.0
        i_b = 0.0
        psi_a = 0.0
        psi_b = 0.0
        w = 0.0
        for k in range(n):
            out[m, 0, k] = i_a
            out[m, 1, k] = i_b
            out[m, 2, k] = w * inv_p
            if k == n - 1:
                break
            va0, vb0, vam, vbm, va1, vb1 = _ref_stage_voltages(v_a, v_b, k, linear)
            i_a, i_b, psi_a, psi_b, w = _ref_rk4(c, i_a, i_b, psi_a, psi_b, w,
                                                 va0, vb0, vam, vbm, va1, vb1, h)
            if _ref_diverged(i_a, i_b, psi_a, psi_b, w):
                break
    return out


# -- fixtures ------------------------------------------------------------------------------
def _record(waveform: str):
    """0.2 s start-up then 0.3 s with the stator shorted: the rotor turns, brakes and, with a
    large Coulomb friction, stops (exercising break-away, the no-reversal stop and stiction)."""
    test = StartupStopTest(cycles=10, waveform=waveform)
    _, v_a, v_b = test.startup_voltages()
    z = np.zeros(3600)
    v_a, v_b = np.concatenate([v_a, z]), np.concatenate([v_b, z])
    meas = ref_outputs_batch(coefficients(PAPER_MOTOR.vector()[None], 1), v_a, v_b, waveform == "sinusoidal",
                             test.sample_time, 1.0)[0]
    return v_a, v_b, waveform == "sinusoidal", test.sample_time, meas


@pytest.fixture(scope="module", params=["six_step", "sinusoidal"])
def record(request):
    return _record(request.param)


def _population(n=61, seed=0):
    rng = np.random.default_rng(seed)
    theta = PAPER_MOTOR.vector()[None] * rng.uniform(0.5, 1.6, (n, 7))
    theta[0] = PAPER_MOTOR.vector()
    theta[1:9, 6] = rng.uniform(0.5, 3.0, 8)  # strong Coulomb friction: stops during the short circuit
    theta[9, 6] = 50.0  # never breaks away
    theta[10, 6] = 0.0  # no Coulomb friction
    theta[11:14, 2] = theta[11:14, 1] * 1.5  # Le > Ls: invalid (NaN row)
    theta[14:17, 2] = theta[14:17, 1] * 1e-6  # tiny leakage: RK4 at the sample time diverges
    theta[17, 4] = -1.0  # negative inertia: invalid
    return coefficients(theta, 1)


def _args(record, exponent):
    v_a, v_b, linear, h, meas = record
    return (v_a, v_b, linear, h, meas[0], meas[1], meas[2], 1.0, np.array([1.0, 2.0, 0.5]), exponent)


# -- tests ---------------------------------------------------------------------------------
def test_population_exercises_friction_and_divergence(record):
    coef = _population()
    out = ref_outputs_batch(coef, *record[:4], 1.0)
    speed = out[:, 2]
    stopped = [m for m in range(1, 9) if np.nanmax(speed[m]) > 1.0 and np.any(speed[m, -100:] == 0.0)]
    assert len(stopped) >= 3  # the no-reversal stop and stiction at rest are reached
    assert np.all(speed[9] == 0.0)  # stiction holds the rotor throughout
    assert np.all(np.isnan(out[11:14])) and np.all(np.isnan(out[17]))
    assert np.all(np.isnan(out[14:17, :, -1]))  # diverged


@pytest.mark.parametrize("exponent", [1, 2])
def test_cost_equals_previous_kernel_bit_for_bit(record, exponent):
    coef = _population()
    args = _args(record, exponent)
    ref = ref_cost_batch(coef, *args)
    got = startup_cost_batch(coef, *args)
    np.testing.assert_array_equal(got, ref)  # exact, inf included
    assert np.all(np.isinf(got[11:18])) and np.all(np.isfinite(got[:11]))
    assert not np.isnan(got).any()


def test_outputs_equal_previous_kernel_bit_for_bit(record):
    coef = _population()
    ref = ref_outputs_batch(coef, *record[:4], 1.0)
    got = startup_outputs_batch(coef, *record[:4], 1.0)
    np.testing.assert_array_equal(got, ref)  # NaN where the reference has NaN


@pytest.mark.parametrize("threads", [1, 2])
def test_cost_independent_of_threads_chunks_order_and_company(record, threads):
    if threads > numba.config.NUMBA_NUM_THREADS:
        pytest.skip("not enough numba threads")
    coef = _population()
    args = _args(record, 1)
    ref = ref_cost_batch(coef, *args)
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(threads)
        np.testing.assert_array_equal(startup_cost_batch(coef, *args), ref)
        for lanes in (1, 3, 8, LANES):
            for blocks in (1, 2, 5):
                np.testing.assert_array_equal(_cost_batch(coef, *args, lanes, blocks), ref)
        perm = np.random.default_rng(1).permutation(len(coef))
        np.testing.assert_array_equal(startup_cost_batch(coef[perm], *args), ref[perm])
        for sub in (slice(0, 1), slice(5, 6), slice(3, 12), slice(20, 37)):
            part = np.ascontiguousarray(coef[sub])
            np.testing.assert_array_equal(startup_cost_batch(part, *args), ref[sub])
        out = _outputs_batch(coef, *args[:4], 1.0, 3, 2)
        np.testing.assert_array_equal(out, ref_outputs_batch(coef, *args[:4], 1.0))
    finally:
        numba.set_num_threads(before)


def test_degenerate_populations(record):
    args = _args(record, 1)
    assert startup_cost_batch(np.empty((0, 10)), *args).shape == (0,)
    bad = np.full((5, 10), np.nan)
    assert np.all(startup_cost_batch(bad, *args) == np.inf)
    assert np.all(np.isnan(startup_outputs_batch(bad, *args[:4], 1.0)))
    # every lane of a chunk diverging (early stop) still gives +inf for each, never NaN
    theta = PAPER_MOTOR.vector()[None].repeat(20, 0)
    theta[:, 2] = theta[:, 1] * np.geomspace(1e-7, 1e-6, 20)
    cost = startup_cost_batch(coefficients(theta, 1), *args)
    assert np.all(cost == np.inf)


def test_concurrent_calls_from_python_threads(record):
    """The block functions release the GIL and share no state: calls from several Python
    threads at once give the same bits as one call."""
    from concurrent.futures import ThreadPoolExecutor

    coef = _population()
    args = _args(record, 2)
    ref = ref_cost_batch(coef, *args)
    with ThreadPoolExecutor(3) as ex:
        results = list(ex.map(lambda _: startup_cost_batch(coef, *args), range(6)))
    for r in results:
        np.testing.assert_array_equal(r, ref)


@numba.njit(cache=True)
def ref_simulate_states(c, v_a, v_b, linear, h, substeps, x0):
    """The previous simulate_states (stepper built on motor.state_derivative)."""
    n = v_a.shape[0]
    out = np.empty((n, 5))
    i_a, i_b, psi_a, psi_b, w = x0[0], x0[1], x0[2], x0[3], x0[4]
    hs = h / substeps
    for k in range(n):
        out[k, 0] = i_a
        out[k, 1] = i_b
        out[k, 2] = psi_a
        out[k, 3] = psi_b
        out[k, 4] = w
        if k == n - 1:
            break
        va0, vb0 = v_a[k], v_b[k]
        dva = v_a[k + 1] - va0 if linear else 0.0
        dvb = v_b[k + 1] - vb0 if linear else 0.0
        for j in range(substeps):
            f0 = j / substeps
            fm = (j + 0.5) / substeps
            f1 = (j + 1.0) / substeps
            i_a, i_b, psi_a, psi_b, w = _ref_rk4(
                c, i_a, i_b, psi_a, psi_b, w,
                va0 + f0 * dva, vb0 + f0 * dvb,
                va0 + fm * dva, vb0 + fm * dvb,
                va0 + f1 * dva, vb0 + f1 * dvb,
                hs,
            )
    return out


@pytest.mark.parametrize("substeps", [1, 4])
def test_simulate_states_equals_state_derivative_stepper(record, substeps):
    """The plant (simulate_states) uses the branch-free derivative; its trajectories equal a
    stepper built on motor.state_derivative bit for bit, through break-away, stops and stiction."""
    v_a, v_b, linear, h, _ = record
    coef = _population()
    for m in (0, 1, 2, 5, 9, 10):
        x0 = np.zeros(5)
        np.testing.assert_array_equal(simulate_states(coef[m], v_a, v_b, linear, h, substeps, x0),
                                      ref_simulate_states(coef[m], v_a, v_b, linear, h, substeps, x0))
    # from a turning state into a long short-circuit: coasts to rest, then stiction holds
    x0 = np.array([1.0, -2.0, 0.5, 0.3, 300.0])
    z = np.zeros(20000)
    for m in (0, 3):
        got = simulate_states(coef[m], z, z, False, h, substeps, x0)
        np.testing.assert_array_equal(got, ref_simulate_states(coef[m], z, z, False, h, substeps, x0))
    assert got[-1, 4] == 0.0 and got[5, 4] > 0.0

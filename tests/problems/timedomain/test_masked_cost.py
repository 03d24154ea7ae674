"""The current-sample mask (``StartupRecord.weight``) in the compiled cost and in the residuals:
masked samples add nothing whatever their value, the model is simulated through them, and
without a mask the cost is the one it was before the mask existed, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from benchmark.problems.timedomain.data import StartupDataset, StartupRecord
from benchmark.problems.timedomain.motor import coefficients
from benchmark.problems.timedomain.problem import TimeDomainProblem
from benchmark.problems.timedomain.simulation import (
    _cost_batch,
    simulate_states,
    startup_cost_batch,
    startup_outputs_batch,
)

TRUTH = np.array([4.96434, 0.1075, 0.01098, 1.55618, 0.00642, 0.00033, 0.04297])
W = np.array([1.0, 1.0, 0.5])

# Costs of _case() computed by the kernel before the mask was added (float.hex), for
# (linear, exponent) and the first three candidates.
GOLDEN = {
    (True, 1): ["0x1.7de24f368beeap+8", "0x1.23cbacba97a83p+16", "0x1.c38dd6445492dp+16"],
    (True, 2): ["0x1.2be6bba2ead04p+5", "0x1.d9bea96a6a48cp+21", "0x1.370c755752187p+23"],
    (False, 1): ["0x1.6f30f15874b32p+10", "0x1.24567866f3d87p+16", "0x1.c2cb6d782ddb8p+16"],
    (False, 2): ["0x1.f5df777e48c29p+8", "0x1.da3c5af9e3ae1p+21", "0x1.36a4d787c8a9dp+23"],
}


def _case():
    n, h = 3000, 1e-4
    t = np.arange(n) * h
    th = 2 * np.pi * 50 * t
    v_a = np.ascontiguousarray(300 * np.cos(th) * (t > 0.0013))
    v_b = np.ascontiguousarray(300 * np.sin(th) * (t > 0.0013))
    out = startup_outputs_batch(coefficients(TRUTH[None, :], 1), v_a, v_b, True, h, 1.0)[0]
    k = np.arange(n)
    i_a = np.ascontiguousarray(out[0] + 0.05 * np.sin(0.37 * k))
    i_b = np.ascontiguousarray(out[1] + 0.05 * np.cos(0.91 * k))
    w = np.ascontiguousarray(out[2] + 0.2 * np.sin(1.3 * k))
    X = TRUTH[None, :] * np.array([[1, 1, 1, 1, 1, 1, 1], [1.1, 0.95, 1.05, 0.9, 1.2, 1, 1],
                                   [0.8, 1.3, 0.7, 1.4, 0.6, 2, 0.5]])
    X = np.vstack([X] * 7)[:19]
    return v_a, v_b, i_a, i_b, w, h, X


@pytest.mark.parametrize("linear", [True, False])
@pytest.mark.parametrize("exponent", [1, 2])
def test_unmasked_cost_is_bit_identical_to_before(linear, exponent):
    v_a, v_b, i_a, i_b, w, h, X = _case()
    coef = coefficients(X, 1)
    got = startup_cost_batch(coef, v_a, v_b, linear, h, i_a, i_b, w, 1.0, W, exponent)
    assert [x.hex() for x in got[:3]] == GOLDEN[(linear, exponent)]
    # an all-True mask is the unmasked path, whatever the chunk width and the blocks
    ones = np.ones(len(v_a), bool)
    for lanes, blocks in ((16, 1), (3, 2), (1, 3)):
        same = _cost_batch(coef, v_a, v_b, linear, h, i_a, i_b, w, 1.0, W, exponent, lanes, blocks, ones)
        assert np.array_equal(same, got)


@pytest.mark.parametrize("exponent", [1, 2])
def test_masked_current_samples_add_nothing(exponent):
    v_a, v_b, i_a, i_b, w, h, X = _case()
    coef = coefficients(X, 1)
    used = np.ones(len(v_a), bool)
    used[10:40] = False
    used[1500:1510] = False
    masked = startup_cost_batch(coef, v_a, v_b, True, h, i_a, i_b, w, 1.0, W, exponent, used)
    # corrupting the masked current samples (even with NaN) changes nothing, bit for bit
    bad_a, bad_b = i_a.copy(), i_b.copy()
    bad_a[~used] = np.nan
    bad_b[~used] = 1e6
    again = startup_cost_batch(coef, v_a, v_b, True, h, bad_a, bad_b, w, 1.0, W, exponent, used)
    assert np.array_equal(again, masked)
    # and it is the sum over the samples that count (the speed of masked instants still counts)
    sim = startup_outputs_batch(coef, v_a, v_b, True, h, 1.0)
    e = np.abs(np.stack([i_a, i_b, w])[None] - sim) ** exponent
    ref = (W[0] * e[:, 0, used]).sum(axis=1) + (W[1] * e[:, 1, used]).sum(axis=1) + (W[2] * e[:, 2]).sum(axis=1)
    np.testing.assert_allclose(masked, ref, rtol=1e-11)
    full = startup_cost_batch(coef, v_a, v_b, True, h, i_a, i_b, w, 1.0, W, exponent)
    assert np.all(masked < full)
    with pytest.raises(ValueError, match="current_weight"):
        startup_cost_batch(coef, v_a, v_b, True, h, i_a, i_b, w, 1.0, W, exponent, used[:-1])


def test_problem_honours_the_record_weight():
    v_a, v_b, i_a, i_b, w, h, _ = _case()
    used = np.ones(len(v_a), bool)
    used[12:30] = False
    t = np.arange(len(v_a)) * h

    def problem(i_alpha, weight):
        rec = StartupRecord(t=t, v_alpha=v_a, v_beta=v_b, i_alpha=i_alpha, i_beta=i_b, speed=w, weight=weight)
        ds = StartupDataset(pole_pairs=1, sample_time=h, input_hold="linear", startups=[rec], stops=[])
        return TimeDomainProblem(ds, TRUTH * 0.5, TRUTH * 2, exponent=2)

    corrupt = i_a.copy()
    corrupt[~used] += 50.0
    X = TRUTH[None, :] * np.array([[1.0] * 7, [1.05, 1, 1, 1, 0.9, 1, 1]])
    clean, dirty = problem(i_a, used), problem(corrupt, used)
    assert np.array_equal(clean.evaluate(X), dirty.evaluate(X))
    assert not np.array_equal(problem(corrupt, None).evaluate(X), clean.evaluate(X))
    r = dirty.residuals_batch(X)
    n = len(v_a)
    assert np.all(r[:, :n][:, ~used] == 0.0) and np.all(r[:, n:2 * n][:, ~used] == 0.0)
    # the residuals' sum of squares is the (eq. 14) cost, mask included
    np.testing.assert_allclose((r**2).sum(axis=1), dirty.evaluate(X), rtol=1e-9)
    # fit quality sees only the samples that count
    sizes = {name: len(res) for name, res, _ in dirty.fit_channels(TRUTH)}
    assert sizes["i_alpha"] == sizes["i_beta"] == int(used.sum()) and sizes["speed"] == n


def test_reference_stepper_with_one_substep_is_the_model():
    v_a, v_b, *_ , h, _ = _case()
    coef = coefficients(TRUTH[None, :], 1)
    for linear in (True, False):
        states = simulate_states(coef[0], v_a, v_b, linear, h, 1, np.zeros(5))
        out = startup_outputs_batch(coef, v_a, v_b, linear, h, 1.0)[0]
        assert np.array_equal(states[:, 0], out[0]) and np.array_equal(states[:, 1], out[1])

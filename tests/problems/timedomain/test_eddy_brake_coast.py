"""The free coast with an eddy-current brake still excited: no closed form, integrated by
``free_coast._brake_coast``; checked against SciPy's adaptive integrator, and the load's
``load_step_crit`` reaching the rows and the kernel's law."""

import numpy as np
from scipy.integrate import solve_ivp

from benchmark.problems.timedomain.diagnosis.free_coast import LANES, FreeCoast, _brake_coast
from benchmark.problems.timedomain.extended_rows import IDX
from benchmark.problems.timedomain.load_effect import LoadTorque

W_REF, J, FV, A, B_A, R = 157.0, 0.05, 0.001, 0.2, 0.02, 2.0


def _reference(t, w0, tau, r=R):
    T_b = B_A * W_REF

    def f(_, y):
        u = y[1] if tau > 0 else y[0] / W_REF
        d = -(A + FV * y[0] + T_b * u * (1 + r * r) / (1 + (r * u) ** 2)) / J
        return [d, (y[0] / W_REF - y[1]) / tau if tau > 0 else 0.0]

    sol = solve_ivp(f, (0, t[-1]), [w0, w0 / W_REF], t_eval=t, rtol=1e-11, atol=1e-11, method="LSODA",
                    events=lambda _, y: y[0])
    w = np.zeros_like(t)
    w[: sol.y.shape[1]] = np.clip(sol.y[0], 0.0, None)
    return w


def test_the_brakes_coast_follows_its_law_with_and_without_the_fields_lag():
    t = np.arange(0.0, 5.0, 1e-3)
    col = lambda v: np.full((2, 1), v)  # noqa: E731
    coast = FreeCoast(t, col(J), col(FV + B_A), col(A), col(0.0), col(B_A), np.array([[0.0], [0.05]]),
                      col(R), col(W_REF))
    w = coast.speed(col(150.0))
    for k, tau in enumerate((0.0, 0.05)):
        ref = _reference(t, 150.0, tau)
        assert np.max(np.abs(w[k] - ref)) < 1e-5  # rad/s, of 150, the stop's instant included
    # the brake's torque peaks at its critical speed (W_REF / R) below W_REF: below W_REF it brakes
    # more than the linear law of the same torque at W_REF, and the coast stops sooner
    linear = FreeCoast(t, col(J), col(FV + B_A), col(A), col(0.0), col(B_A), col(0.0)).speed(col(150.0))
    assert 2.5 < t[np.argmax(w[0] <= 0)] < 3.5 and linear[0, -1] > 5.0  # stopped near 3 s, the linear still turns
    assert np.all(w[0, 1:200] < linear[0, 1:200])


def test_a_lag_shorter_than_the_stops_sampling_is_followed_within_each_step():
    """The field's lag down to a tenth of the stop's 1 ms sampling (the load's lag goes down to one
    sample of the start record) is solved exactly over each Heun step for a speed linear across it:
    within 2e-4 rad/s of SciPy's LSODA at the steepest law (``r`` 5) and 2e-5 at ``r`` 2 (the former
    step, an input held at the step's mean, was 1e-3 and 2.5e-3 off there); the stop's own sample,
    where the reference crosses zero between samples, is left out."""
    t = np.arange(0.0, 5.0, 1e-3)
    for r, bound in ((2.0, 2e-5), (5.0, 2e-4)):
        for tau in (1e-4, 5e-4, 2e-3):
            for w0 in (150.0, 40.0):
                ref = _reference(t, w0, tau, r)
                w = _brake_coast(t, *(np.array([v]) for v in (w0, J, FV, A, 0.0, B_A * W_REF, W_REF, r, tau)))[0]
                stop = int(np.argmax(ref <= 0)) if np.any(ref <= 0) else len(t)
                away = np.abs(np.arange(len(t)) - stop) > 1
                assert np.max(np.abs(w - ref)[away]) < bound, (r, tau, w0)
                assert stop < len(t) and abs(int(np.argmax(w <= 0)) - stop) <= 1  # it stops there too


def test_the_brakes_critical_speed_reaches_the_rows():
    class Ctx:
        torque_scale, record_duration, sample_time, w_sync = 10.0, 1.0, 1e-4, 157.0

    load = LoadTorque()
    lo, hi = load.extra_bounds(Ctx)
    assert len(lo) == len(load.extra_names) == 8 and hi[7] == 5.0  # critical speed down to 0.2 w_sync
    extras = np.array([[0.0, 0.0, 0.3, 0.5, 1.0, 0.05, 1.0, 2.5]])
    rows = load.augment(np.zeros((1, len(IDX))), extras, Ctx)
    assert rows[0, IDX["r_crit"]] == 2.5 and rows[0, IDX["T_s"]] == 3.0
    assert load.describe_fit(extras, Ctx)["critical_speed_over_w_sync"] == 0.4


def test_rows_integrated_side_by_side_equal_each_row_alone():
    """``_brake_coast`` integrates a row whose dynamics are slow beside the sampling by Runge-Kutta
    steps of its own, and the others by Heun's steps, rows with the same number of sub-steps side by
    side in groups of ``LANES``: each row's speed must be the one it has alone, bit for bit,
    whatever rows come with it and in whatever order (here 27 rows: no lag and a 50 ms lag take
    Runge-Kutta steps of several samples, lags of a tenth and a half of a sample Heun's steps on the
    samples, more rows of one count than a group holds; three rows stop within the record)."""
    t = np.arange(0.0, 4.0, 1e-3)
    rng = np.random.default_rng(3)
    n = 27
    tau = np.where(np.arange(n) % 4 == 0, 0.0, rng.choice([1e-4, 5e-4, 5e-4, 0.05], n))
    args = [np.full(n, J) * rng.uniform(0.8, 1.2, n), np.full(n, FV), np.full(n, A) * rng.uniform(0.5, 1.5, n),
            np.zeros(n), np.full(n, B_A * W_REF), np.full(n, W_REF), np.full(n, R), tau]
    w0 = rng.uniform(20.0, 150.0, n)
    w0[:3] = 5.0  # these stop within the record
    together = _brake_coast(t, w0, *args)
    assert (together[:3, -1] == 0).all() and (together[3:, 1] > 0).all()
    assert np.sum(tau == 5e-4) > LANES and np.sum(tau == 1e-4) > 0 and np.sum(tau == 0.05) > 0
    for k in rng.permutation(n):
        alone = _brake_coast(t, w0[k:k + 1], *(a[k:k + 1] for a in args))
        np.testing.assert_array_equal(together[k], alone[0])

"""The diagnosis's fitting engine: fits side by side give what they give alone, each distinct
kernel row is simulated once, the free coast's closed form, and the linearised score tests."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from benchmark.core.effects import load_effects
from benchmark.problems.timedomain.diagnosis import engine
from benchmark.problems.timedomain.diagnosis.fit import DiagnosisData, JointModel
from benchmark.problems.timedomain.diagnosis.free_coast import FreeCoast
from benchmark.problems.timedomain.diagnosis.kernel_cache import KernelCache
from benchmark.problems.timedomain.diagnosis.pipeline import base_context, friction_scale
from benchmark.problems.timedomain.diagnosis.score_tests import score_tests
from benchmark.problems.timedomain.extended import IDX, base_rows, simulate_extended_batch
from benchmark.problems.timedomain.kernel_pool import kernel_budget, kernel_threads
from tests.conftest import PAPER_MOTOR, compose_config

EFFECTS = load_effects("timedomain")
TRUE = {k: getattr(PAPER_MOTOR, k) for k in ("Rs", "Ls", "Le", "Rr", "J", "fv", "fc")}


@pytest.fixture(scope="module")
def offset_record():
    """A 0.2 s six-step start with a 3 s stop and voltage/current offsets (noisy), ready for the fits."""
    from synthetic.timedomain import make_dataset

    cfg = compose_config(["noise=noisy", "motor.test.cycles=10", "motor.test.stop_duration=3",
                          "effects=[sensor_offset]", "+effect_size.sensor_offset=4.0"], name="diagnose")
    ds, _ = make_dataset(cfg)
    data = DiagnosisData.from_dataset(ds)
    ctx = base_context(data, TRUE, ds.dc_link_voltage)
    return data, ctx, friction_scale(TRUE, ctx)


def test_side_by_side_keeps_order_runs_on_workers_and_nests_in_place(monkeypatch):
    monkeypatch.setenv("IMBENCH_FIT_WORKERS", "2")
    names = engine.side_by_side(lambda k: (k, threading.current_thread().name, engine.in_worker()), range(5))
    assert [n[0] for n in names] == list(range(5))
    assert all(n[1].startswith("imbench-fit") and n[2] for n in names)
    inner = engine.side_by_side(lambda k: engine.side_by_side(lambda j: threading.current_thread().name, (k, k)),
                                (0, 1))
    assert all(a == b for a, b in inner)  # a nested map stays in its worker's thread
    with pytest.raises(ZeroDivisionError):
        engine.side_by_side(lambda k: 1 / k, (1, 0, 2))



def test_a_workers_kernels_take_one_core_while_every_worker_is_busy_and_the_idle_cores_after(monkeypatch):
    monkeypatch.setattr(engine.numba, "get_num_threads", lambda: 2)
    monkeypatch.setattr("benchmark.problems.timedomain.kernel_pool.numba.get_num_threads", lambda: 2)
    monkeypatch.setenv("IMBENCH_FIT_WORKERS", "2")
    first_done = threading.Event()
    seen = {}

    def job(k):
        if k == 0:  # ends first
            seen[0] = kernel_threads()
            return
        first_done.wait(5.0)
        for _ in range(500):  # its end is counted just after it returns
            if kernel_threads() == 2:
                break
            threading.Event().wait(0.01)
        seen["alone"] = kernel_threads()

    def run(k):
        try:
            job(k)
        finally:
            if k == 0:
                first_done.set()

    engine.side_by_side(run, (0, 1))
    assert seen[0] == 1 and seen["alone"] == 2
    assert kernel_threads() == 2  # the calling thread: every core
    assert engine.side_by_side(lambda k: kernel_threads(), (0, 1, 2, 3))[0] == 1  # four calls on two workers

def test_kernel_cache_gives_the_kernels_outputs_and_simulates_each_row_once(offset_record):
    data = offset_record[0]
    rows = base_rows(np.array([[TRUE[k] for k in ("Rs", "Ls", "Le", "Rr", "J", "fv", "fc")]] * 3), 1)
    rows[1, IDX["Rs"]] *= 1.01
    rows[2, IDX["J_l"]], rows[2, IDX["k_sh"]] = 0.003, 200.0  # a two-mass row
    batch = rows[[0, 1, 0, 2, 1]]
    batch[4] = np.nan  # an invalid row
    direct = simulate_extended_batch(batch, data.v_alpha, data.v_beta, data.linear, data.sample_time, 1)
    cache = KernelCache(data.v_alpha, data.v_beta, data.linear, data.sample_time, size=2)
    np.testing.assert_array_equal(cache.simulate(batch), direct)
    assert (cache.requested, cache.simulated) == (5, 4)
    np.testing.assert_array_equal(cache.simulate(batch[[3, 4]]), direct[[3, 4]])  # the last two kept
    assert cache.simulated == 4
    with kernel_budget(lambda: 1):  # one thread or several: the same rows, the same outputs
        one = simulate_extended_batch(batch, data.v_alpha, data.v_beta, data.linear, data.sample_time, 1)
    np.testing.assert_array_equal(one, direct)


def _stop_afresh(model, X):
    """The recorded stop of each row of ``X`` computed alone, as :meth:`JointModel.recorded_stop`
    did before it kept coasts: the sensors undone, the start profiled, the coast afresh."""
    d, out = model.data, []
    for x in X:
        x = x[None, :]
        rows = model.rows(x)
        y, w0 = d.stop_speed[None, :], np.full((1, 1), float(d.stop_w0))
        for eff, s in reversed(model._measure_order):
            y, w0 = eff.stop_true_speed(y, x[:, s], model.ctx), eff.stop_true_speed(w0, x[:, s], model.ctx)
        coast, h = model.coast(x, rows), 1e-3 * max(abs(float(d.stop_w0)), 1.0)
        with np.errstate(all="ignore"):
            base = coast.speed(w0)
            D = (coast.speed(w0 + h) - base) / h
            step = np.nansum((y - base) * D, axis=1, keepdims=True) / np.maximum(np.nansum(D * D, axis=1,
                                                                                     keepdims=True), 1e-300)
        limit = 0.05 * abs(float(d.stop_w0))
        stop = coast.speed(w0 + np.clip(np.nan_to_num(step), -limit, limit))
        for eff, s in model._measure_order:
            stop = eff.measure_stop(stop, x[:, s], model.ctx, d.stop_t, d.stop_speed)
        out.append(stop[0])
    return np.array(out)


def test_the_kept_coasts_are_the_stop_computed_afresh_bit_for_bit(offset_record):
    """Rows of every coast (friction alone, a fan load, a DC generator's lag, an eddy-current
    brake's integrated law) beside a tachometer, in one batch with repeats and columns that do
    not move the stop (a Jacobian's): each row's recorded stop equals the one computed alone,
    and a coast already computed is not computed again."""
    data, ctx, fcs = offset_record
    data.coasts = type(data.coasts)()  # a fresh store: the module's other tests share the record
    model = JointModel(data, 2, [EFFECTS["load_torque"], EFFECTS["speed_sensor_gain"]], ctx, TRUE, fcs)
    base = [TRUE[n] for n in model.base_names]
    load = {"fan": [0.0, 0.3, 0.0, 0.5, 0.0, 1e-4, 1.0, 0.0], "generator": [0.0, 0.0, 0.4, 0.1, 1.0, 0.02, 1.0, 0.0],
            "brake": [0.0, 0.0, 0.4, 0.1, 1.0, 0.05, 1.0, 1.5], "constant": [0.2, 0.0, 0.0, 0.5, 0.0, 1e-4, 1.0, 0.0]}
    tach = [0.01, 0.002, 0.003, -0.001, 0.0]
    X = np.array([base + load[k] + tach for k in ("fan", "generator", "brake", "constant")])
    rs, gain = model.names.index("Rs"), model.names.index("speed_sensor_gain.tach_gain_error")
    moved = X[[0, 0, 1, 2, 3, 2]].copy()
    moved[1, rs] *= 1.01  # the electrical part: the same coast
    moved[5, gain] += 1e-4  # the tachometer: the record undone differently
    before = data.coasts.computed
    got = model.recorded_stop(moved, model.rows(moved))
    np.testing.assert_array_equal(got, _stop_afresh(model, moved))
    assert data.coasts.computed - before == 5  # the Rs column's coast was the first row's
    again = model.recorded_stop(moved[[4, 1]], model.rows(moved[[4, 1]]))
    np.testing.assert_array_equal(again, got[[4, 1]])
    assert data.coasts.computed - before == 5  # kept


def _at_rest_from_first_stop(w):
    down = ~(w > 0)
    if down.any():
        w[np.argmax(down):] = 0.0
    return w


def test_free_coast_is_the_closed_form_of_the_coast():
    """Against the closed forms written out here: exponential decay to the Coulomb offset, and
    with a fan load the tangent form; the shaft at rest once stopped."""
    t = np.linspace(0.0, 30.0, 3001)
    J, fv = np.array([[0.0064], [0.0064]]), np.array([[3e-4], [3e-4]])
    A, C = np.array([[0.04], [0.04]]), np.array([[0.0], [2e-6]])
    w = FreeCoast(t, J, fv, A, C).speed(np.array([[300.0], [300.0]]))
    tau, c = J[0, 0] / fv[0, 0], A[0, 0] / J[0, 0]
    expo = _at_rest_from_first_stop((300.0 + tau * c) * np.exp(-t / tau) - tau * c)
    np.testing.assert_allclose(w[0], expo, rtol=1e-13, atol=1e-12)
    q = np.sqrt(4 * A[1, 0] * C[1, 0] - fv[1, 0] ** 2)
    phi0 = np.arctan((2 * C[1, 0] * 300.0 + fv[1, 0]) / q)
    fan = _at_rest_from_first_stop((-fv[1, 0] + q * np.tan(phi0 - q * t / (2 * J[1, 0]))) / (2 * C[1, 0]))
    np.testing.assert_allclose(w[1], fan, rtol=1e-10, atol=1e-9)
    stops = [int(np.argmax(row == 0)) for row in w]
    assert 0 < stops[1] < stops[0] < len(t) - 1  # both stop inside the record, the fan-loaded one sooner


def test_fits_side_by_side_equal_the_fits_one_after_the_other(offset_record, monkeypatch):
    data, ctx, fcs = offset_record
    a, b = data.folds()
    models = [JointModel(data, 2, effects, ctx, TRUE, fcs) for effects in ([], [EFFECTS["sensor_offset"]])]
    jobs = [(m, mask) for m in models for mask in (a, b)]

    def fit(job):
        m, mask = job
        x0 = np.concatenate([[TRUE[n] * 1.05 for n in m.base_names]] + [e.extra_starts(ctx)[0] for e in m.effects])
        return m.fit(x0, mask, 3)

    monkeypatch.setenv("IMBENCH_FIT_WORKERS", "1")
    alone = [fit(j) for j in jobs]
    monkeypatch.setenv("IMBENCH_FIT_WORKERS", "2")
    together = engine.side_by_side(fit, jobs)
    for x, y in zip(alone, together, strict=True):
        np.testing.assert_array_equal(x, y)


def test_score_tests_rank_the_injected_effect_first_and_predict_the_fits(offset_record):
    """The record's offsets: sensor_offset leads the candidates with most of the gap a base fit
    leaves; the held-out chi^2 the step predicts for the leader and for a heating (which takes
    part of an offset's DC signature into the resistances) are those of their fits (fold A,
    scored on B) to a tenth of the gap; after the step the offsets (nearly linear) reach it, the
    heating gains part of it."""
    data, ctx, fcs = offset_record
    a, b = data.folds()
    base = JointModel(data, 2, [], ctx, TRUE, fcs)
    x_a = base.fit(np.array([TRUE[n] for n in base.base_names]), a, 8)
    held = float(np.mean(base.residuals(x_a[None])[0][b] ** 2))
    names = ("sensor_offset", "iron_loss", "temperature_drift", "double_cage")
    rows = score_tests(lambda effs: JointModel(data, 2, effs, ctx, TRUE, fcs), [], x_a, a, b,
                       [(EFFECTS[n],) for n in names], ctx)
    assert rows[0]["effect"] == "sensor_offset", rows
    assert held > 10.0 and rows[0]["drop"] > 0.8 * (held - 1.0), (held, rows[0])
    for name in ("sensor_offset", "temperature_drift"):
        m = JointModel(data, 2, [EFFECTS[name]], ctx, TRUE, fcs)
        x = m.fit(np.concatenate([x_a, EFFECTS[name].extra_starts(ctx)[0]]), a, 12)
        fitted = float(np.mean(m.residuals(x[None])[0][b] ** 2))
        row = next(r for r in rows if r["effect"] == name)
        assert abs(row["predicted_heldout_chi2"] - fitted) < 0.1 * held, (name, row, fitted, held)
        # one step of a nonlinear model: at most what the fit reaches, and a gain on its start
        assert fitted - 0.1 * held < row["heldout_chi2"] < row["heldout_chi2_at_start"], (name, row, fitted)
    offset = rows[0]
    assert abs(offset["heldout_chi2"] - offset["predicted_heldout_chi2"]) < 0.1 * held, offset


def test_a_score_test_names_the_parameters_that_change_nothing_at_its_start(offset_record):
    """A load torque linearised at its first start, no torque at all, is seen in that shape
    only: its step's instant, speed, time constant and law change nothing there (their Jacobian
    columns are zero), so its score rates one shape, not the load (motulator, held-out seed 455
    set 8: a load screened 0.02 below the base and fitted to a fifth of it). From a start with a
    step torque they act, but for the brake's law; an offset's four parameters act from its start
    of zeros."""
    data, ctx, fcs = offset_record
    a, b = data.folds()
    base = JointModel(data, 2, [], ctx, TRUE, fcs)
    x_a = np.array([TRUE[n] for n in base.base_names])
    load, offset = EFFECTS["load_torque"], EFFECTS["sensor_offset"]

    def make(effs):
        return JointModel(data, 2, effs, ctx, TRUE, fcs)

    def unseen(row):
        return {n.split(".")[1] for n in row["unseen"]}

    rows = {r["effect"]: r for r in score_tests(make, [], x_a, a, b, [(load,), (offset,)], ctx)}
    assert load.extra_starts(ctx)[0][2] == 0.0  # no step torque at the first start
    assert {"load_step_time", "load_step_speed", "load_step_tau"} <= unseen(rows["load_torque"])
    assert "load_step" not in unseen(rows["load_torque"]) and rows["sensor_offset"]["unseen"] == []

    def with_torque(model, x_fit, new):
        start = np.array(new[0].extra_starts(ctx)[0], float)
        start[2] = 0.5  # a step torque, N m
        start[3] = 0.05  # its instant, s
        return [np.concatenate([x_fit, start])]

    stepped = score_tests(make, [], x_a, a, b, [(load,)], ctx, starts=with_torque)[0]
    assert unseen(stepped) == {"load_step_crit"}  # an eddy-current brake's law: nothing without a brake


def test_a_fit_holds_a_parameter_whose_bounds_coincide(offset_record):
    """The folds' shared instant (``Selector.held_at``) is held by bounds that coincide: the
    fit must leave it there (a zero-width box once let it move by up to 1 in its units)."""
    data, ctx, fcs = offset_record
    model = JointModel(data, 2, [], ctx, TRUE, fcs)
    x0 = np.array([TRUE[n] for n in model.base_names]) * 1.05
    k = model.base_names.index("Rs")
    model.lower[k] = model.upper[k] = x0[k]
    x = model.fit(x0, None, 20)
    assert x[k] == x0[k]
    assert np.all(x >= model.lower) and np.all(x <= model.upper)
    assert model.ssr(x) < model.ssr(x0)  # the others moved


def test_a_candidate_screened_beside_the_same_fit_again_is_not_simulated_again(offset_record):
    """The round after an effect negligible on entry starts from the same fit: the screening of
    the candidates already screened beside it is kept (each depends on that fit and the
    candidate alone); a candidate not screened yet is, and gets what it gets screened alone."""
    from benchmark.problems.timedomain.diagnosis.pipeline import DiagnosisSettings
    from benchmark.problems.timedomain.diagnosis.rule import Rule
    from benchmark.problems.timedomain.diagnosis.selection import Selector, SetFit

    data, ctx, fcs = offset_record
    a, b = data.folds()
    masks = {"A": a, "B": b}

    def selector():
        return Selector(data, DiagnosisSettings(), ctx, dict(TRUE), fcs, masks, Rule(0.3),
                        {n: k for k, n in enumerate(EFFECTS)})

    sel = selector()
    base = sel.model([])
    x = np.array([TRUE[n] for n in base.base_names])
    cur = SetFit(base, {"A": x, "B": x}, masks)
    offset, coupling, drift = EFFECTS["sensor_offset"], EFFECTS["two_mass"], EFFECTS["temperature_drift"]
    first = sel.screen_singles(cur, [offset, coupling])
    simulated = data.kernel.simulated
    assert sel.screen_singles(cur, [coupling, offset]) == {"two_mass": first["two_mass"],
                                                           "sensor_offset": first["sensor_offset"]}
    assert data.kernel.simulated == simulated  # nothing simulated again
    assert first["sensor_offset"] < first["two_mass"]  # the injected offsets screen best
    more = sel.screen_singles(cur, [offset, drift])
    assert data.kernel.simulated > simulated and more["sensor_offset"] == first["sensor_offset"]
    assert more["temperature_drift"] == selector().screen_singles(cur, [drift])["temperature_drift"]

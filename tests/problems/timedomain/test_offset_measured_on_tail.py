"""A fitted ``sensor_offset`` is checked against the offsets the record's steady tail measures.

An offset is a constant, and the conditioning measures it directly on the steady tail (whole
supply periods, where neither supply nor machine has a DC part). A catalogue fit that puts an
offset where that measurement says there is none took up another form's leftover (independent
plant, fresh calibration seed 501 set 15: 0.23 +- 0.05 A fitted beside a channel skew, taking what
the skew's form left of a voltage lag, where the tail measured 0.001 +- 0.006 A); the diagnosis
does not name it: checked only where the tail finds no offset on any channel (a probe's offset
may drift, and a constant fitted to it need not agree with the tail's end), and only on a grid
supply, whose voltage has no DC part of its own."""

from __future__ import annotations

import warnings
from types import SimpleNamespace

import numpy as np
import pytest
import yaml

from benchmark.core.effects import EffectContext, load_effects
from benchmark.problems.timedomain.conditioning import offsets_left, restored
from benchmark.problems.timedomain.data import load_startup_dataset
from benchmark.problems.timedomain.diagnosis.selection import Selector
from benchmark.problems.timedomain.frames import clarke
from synthetic.independent import make_dataset, make_spec, write_dataset

OFFSET = load_effects("timedomain", ["sensor_offset"])["sensor_offset"]
GAIN = load_effects("timedomain", ["speed_sensor_gain"])["speed_sensor_gain"]


def _ctx(left=None, **facts):
    facts = {"input_hold": "linear", "dc_link_voltage": None, **facts}
    if left is not None:
        facts["offsets_left"] = left
    return EffectContext(w_e=314.16, V1=326.6, I_peak=78.8, w_sync=157.08, dc_link_voltage=0.0, E_cu=5000.0,
                         L_M=0.12, L_sigma=0.006, pole_pairs=2, facts=facts)


def _fitted(di_alpha, di_beta, se_alpha, se_beta):
    """Fitted extras (p.u. of the current peak) and their standard errors, from amperes."""
    return np.array([0.0, 0.0, di_alpha, di_beta]) / 78.8, np.array([1e-3, 1e-3, se_alpha, se_beta]) / 78.8


def test_an_offset_the_steady_tail_excludes_is_contradicted_one_it_allows_is_not():
    left = {"i_alpha": (0.0012, 0.0043), "i_beta": (0.0009, 0.0058)}  # plant 501 set 15's tail
    ctx = _ctx(left)
    assert OFFSET.measured_directly(ctx)
    why = OFFSET.contradicted(*_fitted(0.090, 0.23, 0.03, 0.05), ctx)
    # alpha: 0.089 / hypot(0.03, 0.0043) = 2.9 standard errors, within; beta: 0.229 / 0.0503 = 4.6
    assert why is not None and "i_beta" in why and "4.6 standard errors" in why
    assert OFFSET.contradicted(*_fitted(0.090, 0.10, 0.03, 0.05), ctx) is None  # 2.9 and 2.0: both within
    # an offset the tail finds: the fit is not checked, a constant fitted to a drifting probe is a
    # compromise the tail's end need not agree with (held-out plant 414 set 22, a thermal drift:
    # -0.132 +- 0.004 A fitted, -0.099 +- 0.0025 A at the tail, 6.9 standard errors apart)
    drifting = _ctx({"i_alpha": (-0.0992, 0.0025), "i_beta": (0.104, 0.0044)})
    assert OFFSET.contradicted(*_fitted(-0.132, 0.104, 0.004, 0.004), drifting) is None
    # components the tail did not measure (voltages of an inverter's switch states) are not checked
    assert OFFSET.contradicted(np.array([0.01, 0.0, 0.0, 0.0]), np.full(4, 1e-5), ctx) is None
    assert not OFFSET.measured_directly(_ctx()) and not OFFSET.measured_directly(_ctx({}))
    # an inverter's applied voltage may carry a DC of its own (a dead-time asymmetry): the tail's
    # current means are then not the probes' offsets alone (development plant 502 sets 4 and 5, a
    # six-step start with a real offset, whose catalogue fit was 5.9 and 3.4 standard errors off)
    assert not OFFSET.measured_directly(_ctx(left, input_hold="zoh"))
    assert not OFFSET.measured_directly(_ctx(left, dc_link_voltage=540.0))
    assert not GAIN.measured_directly(ctx) and GAIN.contradicted(np.zeros(5), np.ones(5), ctx) is None


def _selector(left, se):
    """A selector whose one fitted set is ``sensor_offset`` (standard errors ``se``, p.u.)."""
    model = SimpleNamespace(effects=[OFFSET], slices=[slice(7, 11)], effect_names=["sensor_offset"],
                            standard_errors=lambda x: np.concatenate([np.ones(7), se]))
    sel = Selector.__new__(Selector)
    sel.ctx = _ctx(left)
    return sel, SimpleNamespace(model=model, names=["sensor_offset"])


def test_the_selection_refuses_a_contradicted_offset_with_the_reason():
    x = np.concatenate([np.ones(7), _fitted(0.09, 0.23, 0.03, 0.05)[0]])
    sel, sf = _selector({"i_beta": (0.0009, 0.0058)}, _fitted(0.09, 0.23, 0.03, 0.05)[1])
    refused = sel.refused(sf, x)
    assert list(refused) == ["sensor_offset"] and refused["sensor_offset"].startswith("fitted on all data its i_beta")
    sel, sf = _selector({"i_beta": (0.21, 0.02)}, _fitted(0.09, 0.23, 0.03, 0.05)[1])  # agrees with the tail
    assert sel.refused(sf, x) == {}


def _offset_record(tmp_path, scenario, seed):
    """A 7.5 kW start of the independent plant with offsets on every channel, loaded (conditioned),
    and its injected offsets as alpha-beta components (V, A)."""
    spec = make_spec("simulink_7k5", scenario, ["sensor_offset"], seed=seed, duration=1.0, sample_rate=10000,
                     forms={"sensor_offset": "both"})
    folder = write_dataset(make_dataset(spec), tmp_path / f"set_{scenario}_{seed}")
    truth = yaml.safe_load((folder / "truth.yaml").read_text())["effects"][0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = load_startup_dataset(folder)
    i_r, i_s = truth["current_offsets"]
    v_alpha, v_beta = clarke(*truth["voltage_offsets"])
    return ds, {"i_alpha": i_r, "i_beta": (i_r + 2 * i_s) / np.sqrt(3.0), "v_alpha": v_alpha, "v_beta": v_beta}


@pytest.mark.parametrize("scenario", ["six_step", "pwm", "dol"])
def test_the_tail_measures_what_a_start_carries_removed_or_put_back(tmp_path, scenario):
    """The conditioning measures the offsets on the steady tail and removes them (an inverter
    start: from the tail; a grid start: from its pre-trigger); what it leaves is zero within the
    tail's standard errors, and with the removal put back it is the injected offset. An inverter's
    switch-state voltages are not measured: no voltage component there."""
    ds, injected = _offset_record(tmp_path, scenario, seed=2)
    assert ds.conditioning_removed == ["sensor_offset"]
    left = offsets_left(ds)
    assert set(left) == ({"i_alpha", "i_beta"} | ({"v_alpha", "v_beta"} if scenario == "dol" else set()))
    assert all(abs(value) < 3 * se and 0 < se < 0.04 for value, se in left.values()), left
    put_back = offsets_left(restored(ds, "sensor_offset"))
    for name, (value, se) in put_back.items():
        assert abs(value - injected[name]) < max(3 * se, 0.01), (name, value, se, injected[name])


def test_the_tails_standard_errors_hold_over_grid_starts(tmp_path):
    """Eight grid starts with offsets on every channel (seeds 4-11): the tail's measurement (with
    the removal put back) against the injected offset, in its own standard errors. 32 components:
    root mean square 1.36, largest 3.03 (seeds 4-15, 48 components: 1.18, one beyond 3): the batch
    means understate the spread by up to a third on this plant, which the check at 3 combined
    standard errors leans on (the fit's own standard error is the larger part there). Asserted:
    not off by a factor of two either way."""
    z = []
    for seed in range(4, 12):
        ds, injected = _offset_record(tmp_path, "dol", seed)
        left = offsets_left(restored(ds, "sensor_offset"))
        z += [(value - injected[name]) / se for name, (value, se) in left.items()]
    z = np.array(z)
    assert len(z) == 32 and 0.5 < np.sqrt(np.mean(z**2)) < 2.0 and np.max(np.abs(z)) < 4.5, z

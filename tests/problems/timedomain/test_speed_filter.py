"""A speed channel's filter is a fact of the instrument (``speed_filter`` in meta.yaml, s): read,
checked and written back; every model of the diagnosis reads its speed through it, on the
start-up and on the stop; the tachometer has no filter of its own to fit."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from benchmark.core.effects import EffectContext, load_effects
from benchmark.core.errors import DataError
from benchmark.problems.timedomain.data import load_startup_dataset, write_startup_dataset
from benchmark.problems.timedomain.diagnosis.fit import DiagnosisData, JointModel
from benchmark.problems.timedomain.speed_filter import first_order_lag
from synthetic.timedomain import make_dataset
from tests.conftest import compose_config, with_meta_key


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    ds, _ = make_dataset(compose_config(["motor.test.cycles=5", "motor.test.stop_duration=1"], name="synthetic"))
    return write_startup_dataset(tmp_path_factory.mktemp("filter") / "set", ds)


def _with(folder, value):
    return with_meta_key(folder, "speed_filter", value)


def test_a_stated_filter_is_read_checked_and_kept(folder, tmp_path):
    ds = _with(folder, 0.004)
    assert ds.speed_filter == 0.004 and ds.facts()["speed_filter"] == 0.004
    again = load_startup_dataset(write_startup_dataset(tmp_path / "again", dataclasses.replace(ds, conditioning=[])))
    assert again.speed_filter == 0.004
    assert _with(folder, None).speed_filter is None
    for bad, words in (("4 ms", "speed_filter"), (-0.001, "0 to 0.1"), (0.5, "0 to 0.1")):
        with pytest.raises(DataError) as err:
            _with(folder, bad)
        assert "meta.yaml" in str(err.value) and words in str(err.value)


def test_the_filter_lags_an_accelerating_shaft():
    """``1/(1 + s tau)`` on a shaft accelerating at ``a``: the reading settles ``tau a`` below the
    speed; a row with ``tau = 0`` passes unchanged."""
    ts, acc = 1e-4, 500.0
    w = np.tile(acc * ts * np.arange(4000), (2, 1))
    out = first_order_lag(w, np.array([0.0, 3e-3]), ts)
    np.testing.assert_array_equal(out[0], w[0])
    assert out[1, -1] == pytest.approx(w[1, -1] - 3e-3 * acc, rel=1e-9)
    np.testing.assert_array_equal(first_order_lag(w, 3e-3, ts), np.vstack([out[1], out[1]]))


def test_every_model_reads_its_speed_through_the_stated_filter(folder):
    """The base model's start-up speed and stop through the stated 4 ms filter, the currents as
    they were; nothing stated, nothing filtered. The tachometer has no lag among its extras."""
    ds = _with(folder, 0.004)
    data = DiagnosisData.from_dataset(ds)
    est = {"Rs": 1.0, "Ls": 0.12, "Le": 0.01, "Rr": 1.0, "J": 0.01, "fv": 1e-3, "fc": 0.02}
    ctx = EffectContext(w_e=314.16, V1=190.0, I_peak=20.0, w_sync=314.16, dc_link_voltage=0.0, E_cu=100.0,
                        L_M=0.11, L_sigma=0.01, sample_time=ds.sample_time, facts=ds.facts())
    plain = JointModel(data, 2, [], dataclasses.replace(ctx, facts={}), est, 1.0)
    filtered = JointModel(data, 2, [], ctx, est, 1.0)
    x = np.array([[est[n] for n in plain.base_names]])
    a, b = plain.simulate(x)[0], filtered.simulate(x)[0]
    sl = data.channel_slices()
    np.testing.assert_array_equal(a[sl["i_alpha"]], b[sl["i_alpha"]])
    np.testing.assert_allclose(b[sl["speed"]], first_order_lag(a[None, sl["speed"]], 0.004, ds.sample_time)[0])
    assert not np.allclose(a[sl["speed"]], b[sl["speed"]])
    stop = sl["stop_speed"]  # the data set has a stop record
    assert 0.0 < np.max(np.abs(a[stop] - b[stop])) < 0.05 * np.max(np.abs(a[stop]))
    assert "tach_lag" not in load_effects("timedomain")["speed_sensor_gain"].extra_names

"""A speed sensor's filter is a fact of the instrument (``speed_filter`` in meta.yaml, s): read,
checked, written back, and it decides how long a filter the tachometer's fit may give its
output (none where nothing is stated)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import yaml

from benchmark.core.effects import EffectContext, load_effects
from benchmark.core.errors import DataError
from benchmark.problems.timedomain.data import load_startup_dataset, write_startup_dataset
from synthetic.timedomain import make_dataset
from tests.conftest import compose_config

LAG = load_effects("timedomain")["speed_sensor_gain"].extra_names.index("tach_lag")


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    ds, _ = make_dataset(compose_config(["motor.test.cycles=5", "motor.test.stop_duration=1"], name="synthetic"))
    return write_startup_dataset(tmp_path_factory.mktemp("filter") / "set", ds)


def _with(folder, value):
    meta = folder / "meta.yaml"
    doc = yaml.safe_load(meta.read_text())
    doc["speed_filter"] = value
    meta.write_text(yaml.safe_dump(doc))
    return load_startup_dataset(folder)


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


def _ctx(**facts):
    return EffectContext(w_e=314.16, V1=190.0, I_peak=20.0, w_sync=314.16, dc_link_voltage=300.0, E_cu=100.0,
                         L_M=0.1, L_sigma=0.01, facts=facts)


def test_the_tachometer_filter_is_searched_up_to_the_stated_one_only():
    tach = load_effects("timedomain")["speed_sensor_gain"]
    lo, hi = tach.extra_bounds(_ctx())
    assert lo[LAG] == hi[LAG] == 0.0  # nothing stated: no filter (the fits leave the lag out)
    assert all(s[LAG] == 0.0 for s in tach.extra_starts(_ctx()))
    assert np.all(lo[:LAG] < hi[:LAG])  # gain, offset and ripple stay free
    lo, hi = tach.extra_bounds(_ctx(speed_filter=0.004))
    assert (lo[LAG], hi[LAG]) == (0.0, pytest.approx(0.005))  # the stated 4 ms with a quarter's tolerance
    lo, hi = tach.extra_bounds(_ctx(speed_filter=0.0))
    assert hi[LAG] == 0.0  # a filter stated as none is none

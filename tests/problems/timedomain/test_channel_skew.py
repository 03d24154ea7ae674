"""A channel skew is a fact of the acquisition (``channel_skew`` in meta.yaml): read, checked,
written back, and it decides whether ``channel_delay`` is a candidate and where its fit searches."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from benchmark.core.effects import load_effects
from benchmark.core.errors import DataError
from benchmark.problems.timedomain.data import load_startup_dataset, write_startup_dataset
from benchmark.problems.timedomain.diagnosis.pipeline import screen
from synthetic.timedomain import make_dataset
from tests.conftest import compose_config, with_meta_key


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    ds, _ = make_dataset(compose_config(["motor.test.cycles=5", "motor.test.stop_duration=1"], name="synthetic"))
    return write_startup_dataset(tmp_path_factory.mktemp("skew") / "set", ds)


def _with(folder, value):
    return with_meta_key(folder, "channel_skew", value)


def test_a_stated_skew_is_read_checked_and_kept(folder, tmp_path):
    assert _with(folder, 0.5).channel_skew == 0.5
    ds = _with(folder, [0.2, -0.3])
    assert ds.channel_skew == (-0.3, 0.2) and ds.facts()["channel_skew"] == (-0.3, 0.2)
    again = load_startup_dataset(write_startup_dataset(tmp_path / "again", dataclasses.replace(ds, conditioning=[])))
    assert again.channel_skew == (-0.3, 0.2)
    for bad, words in (("early", "channel_skew"), (20.0, "within"), ([1.0, 2.0, 3.0], "[low, high]")):
        with pytest.raises(DataError) as err:
            _with(folder, bad)
        assert "meta.yaml" in str(err.value) and words in str(err.value)


def test_channel_delay_is_a_candidate_only_where_a_skew_is_stated(folder):
    effects = load_effects("timedomain")
    facts = {**_with(folder, None).facts(), "base_case": 2}
    keep, excluded = screen(effects, facts)
    assert "channel_delay" not in {e.name for e in keep}
    assert "channel_skew" in next(e["reason"] for e in excluded if e["effect"] == "channel_delay")
    keep, _ = screen(effects, {**facts, "channel_skew": 0.5})
    assert "channel_delay" in {e.name for e in keep}
    np.testing.assert_allclose(np.ravel(effects["channel_delay"].extra_bounds(
        dataclasses.replace(_ctx(), facts={"channel_skew": -1.0}))), [-1.25, -0.75])


def _ctx():
    from benchmark.core.effects import EffectContext

    return EffectContext(w_e=314.16, V1=190.0, I_peak=20.0, w_sync=314.16, dc_link_voltage=300.0, E_cu=100.0,
                         L_M=0.1, L_sigma=0.01)

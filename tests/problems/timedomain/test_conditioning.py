"""Conditioning on load, on records of the independent plant (which shares no code with the
loader): pre-trigger trimmed, sensor offsets recovered, clipped samples masked, clean records
left bit for bit as they are; and the bench keys of meta.yaml."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import yaml

from benchmark.core.errors import DataError
from benchmark.problems.timedomain.data import load_startup_dataset
from synthetic.independent import make_dataset, make_spec, write_dataset


def _bench(tmp_path, effects, seed, forms=None, **kw):
    spec = make_spec("simulink_7k5", "dol", list(effects), seed=seed, duration=1.0, sample_rate=10000,
                     forms=forms, **kw)
    folder = write_dataset(make_dataset(spec), tmp_path / "set")
    truth = yaml.safe_load((folder / "truth.yaml").read_text())
    (folder / "truth.yaml").unlink()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_startup_dataset(folder), truth, folder


def test_pre_trigger_trimmed_and_offsets_recovered(tmp_path):
    ds, truth, folder = _bench(tmp_path, ["sensor_offset"], seed=2, forms={"sensor_offset": "both"})
    raw = np.loadtxt(folder / "startup.csv", delimiter=",", skiprows=1)
    eff = truth["effects"][0]
    # the line voltages appear when the second pole closes (one closed pole carries no current)
    pre = truth["scenario"]["pre_trigger"] + sorted(truth["scenario"]["stagger"])[1]
    rec = ds.startups[0]
    # trimmed to 10 samples before the first pole closed (the record started 46 ms earlier)
    trimmed = len(raw) - len(rec.t)
    assert abs(trimmed * 1e-4 - (pre - 10e-4)) <= 2e-4, (trimmed, pre)
    text = "\n".join(ds.conditioning)
    assert "pre-trigger samples trimmed" in text and "offsets removed" in text
    assert ds.conditioning_removed == ["sensor_offset"]  # named for the diagnosis and the blind scores
    # the alpha-beta offsets left in the conditioned record: the pre-trigger mean is ~0 now
    v_off = np.array(eff["voltage_offsets"])
    v_diff = v_off - v_off.mean()  # a common-mode offset does not reach alpha-beta
    est = {}
    for line in ds.conditioning:
        if "offsets removed" in line or "offsets below significance" in line:
            for part in line.split(": ", 2)[2].split(", "):
                name, value = part.split()[:2]
                est[name] = float(value)
    got_v = np.array([est["v_r"], est["v_s"], est["v_t"]])
    np.testing.assert_allclose(got_v - got_v.mean(), v_diff, atol=0.1)
    np.testing.assert_allclose([est["i_r"], est["i_s"]], eff["current_offsets"], atol=0.02)


def test_hard_clipped_current_samples_are_masked(tmp_path):
    ds, truth, _ = _bench(tmp_path, ["current_sensor_saturation"], seed=5,
                          forms={"current_sensor_saturation": "clip"})
    rec = ds.startups[0]
    assert rec.weight is not None
    n_masked = int((~rec.weight).sum())
    assert n_masked > 20, ds.conditioning
    assert any("hard-clipped" in line for line in ds.conditioning)
    assert "current_sensor_saturation" in ds.conditioning_removed
    # the masked samples are the start-up's peaks: where a phase current sits at the clip level
    level = truth["effects"][0]["level"]
    i_r = rec.i_alpha  # phase R of a three-wire record is alpha (amplitude-invariant Clarke)
    i_s = -0.5 * rec.i_alpha + 0.5 * np.sqrt(3.0) * rec.i_beta
    top = np.maximum(np.abs(i_r), np.abs(i_s))[~rec.weight]
    assert np.median(top) > 0.9 * level


def test_a_clean_synthetic_record_is_left_as_it_is(tmp_path):
    from benchmark.core.harness import load_dataset
    from benchmark.problems.timedomain.conditioning import condition_dataset, offsets_left
    from tests.conftest import compose_config

    ds, _ = load_dataset(compose_config(["noise=noisy"]))
    out = condition_dataset(ds)
    new, old = out.startups[0], ds.startups[0]
    for name in ("t", "v_alpha", "v_beta", "i_alpha", "i_beta", "speed"):  # nothing significant: the very same arrays
        assert getattr(new, name) is getattr(old, name)
    assert any("no significant sensor offset" in line for line in out.conditioning)
    assert out.conditioning_removed == []
    # what the steady tail measured is kept for the diagnosis (alpha-beta, A; no offset in this record)
    measured = new.removed["sensor_offset_measured"]
    assert list(new.removed) == ["sensor_offset_measured"] and set(measured) == {"i_alpha", "i_beta"}
    assert all(abs(value) < 3 * se and 0 < se < 0.05 for value, se in measured.values()), measured
    left = offsets_left(out)  # one record, nothing removed: what is left is what was measured
    assert set(left) == set(measured) and all(left[k] == pytest.approx(measured[k]) for k in left)


def test_bench_keys_of_meta_yaml(tmp_path):
    ds, truth, folder = _bench(tmp_path, [], seed=1)
    assert ds.nameplate["rated_power"] == 7500.0 and ds.nameplate["voltage"] == 400.0
    meta = yaml.safe_load((folder / "meta.yaml").read_text())
    meta |= {"stator_dc_resistance": 0.74, "winding_temperature": 21.5}
    (folder / "meta.yaml").write_text(yaml.safe_dump(meta))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = load_startup_dataset(folder)
    assert ds.stator_dc_resistance == 0.74 and ds.winding_temperature == 21.5
    assert ds.facts() == {"dc_link_voltage": None, "input_hold": "linear", "supply_frequency": 50.0,
                          "has_speed": True, "has_stop": False, "channel_skew": None, "speed_filter": None,
                          "nameplate": ds.nameplate}
    meta["nameplate"]["powr"] = 1.0
    (folder / "meta.yaml").write_text(yaml.safe_dump(meta))
    with pytest.raises(DataError, match=r"nameplate.powr' unknown \(found 'power'|nameplate.powr' unknown"):
        load_startup_dataset(folder)


def test_torque_column_and_no_speed_column(tmp_path):
    ds, truth, folder = _bench(tmp_path, ["load_torque"], seed=3, has_speed=False, has_torque=True,
                               forms={"load_torque": "constant"})
    rec = ds.startups[0]
    assert not ds.has_speed and np.isnan(rec.speed).all()
    assert rec.torque is not None and np.isfinite(rec.torque).all()
    assert np.mean(rec.torque[-1000:]) > 0.05 * np.max(np.abs(rec.torque))  # the load's torque at the end


def test_conditioning_is_reported_in_report_md(tmp_path):
    """What the conditioning did reaches result.json (problem_info) and report.md."""
    from benchmark.core.plotting import write_report
    from benchmark.problems.timedomain.problem import TimeDomainProblem

    ds, _, _ = _bench(tmp_path, ["sensor_offset"], seed=2, forms={"sensor_offset": "both"})
    lo = np.array([0.1, 0.01, 0.001, 0.1, 0.001, 0.0, 0.0])
    info = TimeDomainProblem(ds, lo, lo * 10 + 1.0).describe()
    assert info["conditioning"] == list(ds.conditioning) and info["conditioning"]
    report = write_report(tmp_path, {"problem": "timedomain", "problem_info": info}, [], [])
    text = report.read_text()
    assert "Conditioning on load:" in text
    assert all(f"- {line}" in text for line in ds.conditioning)

"""A multiplexed card's sequence in ``meta.yaml`` (``channel_skew`` as a mapping of channels).

A card converting its channels one after the other skews each phase channel by its own share of
a sample. The independent plant's ``mux_skew`` form (retired from its held-out forms) makes such
a record: ``i_r, v_r, v_s, i_s, v_t`` at 0.25 samples apart, so the current channels are 0 and 0.6
samples late (the slot realised to a tenth of a sample) and, on the grid, the voltage channels
0.2-0.8. Stating only the slot (a number: one skew for all currents, as the blind sets' files
did) leaves the record ``unexplained``; stating the sequence realigns the voltages on reading
and ``channel_delay`` fits the two currents' skews in their stated ratio: explained, at the
skew the card has."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from benchmark.core.errors import DataError
from benchmark.problems.timedomain.channel_timing import delay_phase_currents, fractional_delay, realign
from benchmark.problems.timedomain.data import load_startup_dataset
from synthetic.independent.dataset import make_spec
from tests.conftest import diagnose_with, remade_blind_set


@pytest.fixture(scope="module", params=["six_step", pytest.param("dol", marks=pytest.mark.slow)])
def card_record(request, tmp_path_factory):
    spec = make_spec("paper_1kw", request.param, ["channel_delay"], seed=3, duration=0.5, sample_rate=10000.0,
                     forms={"channel_delay": "mux_skew"})
    spec["effects"][0].update(size=0.25, order=["i_r", "v_r", "v_s", "i_s", "v_t"])
    made, folder = remade_blind_set(spec, tmp_path_factory.mktemp(request.param) / "set")
    return request.param, made, folder


def _state(folder, skew):
    meta = yaml.safe_load((folder / "meta.yaml").read_text())
    meta["channel_skew"] = skew
    (folder / "meta.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))


def test_a_cards_sequence_explains_what_one_skew_for_all_currents_cannot(card_record, tmp_path):
    kind, made, folder = card_record
    slot = made.truth["effects"][0]["achieved_size"]
    assert slot == pytest.approx(0.2)  # 0.25 realised to the plant's tenth of a sample
    sequence = {"i_r": 0.0, "v_r": slot, "v_s": 2 * slot, "i_s": 3 * slot, "v_t": 4 * slot}
    if kind != "dol":  # an inverter's voltages come from its gates, not from the card
        sequence = {"i_r": 0.0, "i_s": 3 * slot}
    cands = ["channel_delay", "main_saturation", "sensor_offset"]
    _state(folder, slot)
    one = diagnose_with(folder, tmp_path / "one", cands)
    assert one["verdict"] == "unexplained" and one["gap_before"]["heldout_rms_over_noise"] > 2.5
    _state(folder, sequence)
    doc = diagnose_with(folder, tmp_path / "seq", cands)
    assert doc["verdict"] == "channel_delay" and doc["status"] == "explained", doc["selection"]
    assert doc["gap_after"]["heldout_rms_over_noise"] < doc["gap_after"]["noise_band"][1]
    fit = doc["per_effect"][0]
    assert fit["physical"]["i_r_skew_samples"] == 0.0
    skew = fit["parameters"]["skew"]
    assert skew["value"] == pytest.approx(3 * slot, abs=3 * skew["standard_error"] + 0.03)


def test_a_sequence_must_name_phase_channels_of_the_record(tmp_path):
    t = np.arange(400) / 1e4
    cols = {"t": t, "v_alpha": np.cos(314 * t), "v_beta": np.sin(314 * t), "i_r": np.cos(314 * t),
            "i_s": np.cos(314 * t - 2.094)}
    (tmp_path / "startup.csv").write_text("t,v_alpha,v_beta,i_r,i_s\n" + "\n".join(
        ",".join(f"{cols[k][n]:.9g}" for k in cols) for n in range(len(t))))
    meta = {"kind": "startup", "pole_pairs": 1, "sample_time": 1e-4, "conditioning": False}
    for skew, match in (({"i_q": 0.2}, r"channel_skew\.i_q' unknown"),
                        ({"v_r": 0.2}, r"gives \['v_r'\] a skew, but the records hold v_alpha, v_beta"),
                        ({"i_s": 9.0}, r"within \+-8 samples")):
        (tmp_path / "meta.yaml").write_text(yaml.safe_dump({**meta, "channel_skew": skew}))
        with pytest.raises(DataError, match=match):
            load_startup_dataset(tmp_path)
    (tmp_path / "meta.yaml").write_text(yaml.safe_dump({**meta, "channel_skew": {"i_s": 0.4}}))
    assert load_startup_dataset(tmp_path).channel_skew == {"i_s": 0.4}


def test_realignment_and_per_phase_delays_undo_what_the_card_did():
    t = np.arange(2000) * 1e-4
    w = 2 * np.pi * 50
    phases = np.stack([np.cos(w * t - k * 2 * np.pi / 3) for k in range(3)], axis=1)
    lags = {"v_r": 0.2, "v_s": 0.4, "v_t": 0.8}
    late = np.stack([np.cos(w * (t - lags[c] * 1e-4) - k * 2 * np.pi / 3) for k, c in enumerate(lags)], axis=1)
    back = realign(late, lags)
    assert np.max(np.abs(back[5:-5] - phases[5:-5])) < 1e-5  # 4-point Lagrange at 100 samples a period
    a, b = phases[:, 0], (phases[:, 1] - phases[:, 2]) / np.sqrt(3)
    i_ab = np.stack([a, b])[None]
    out = delay_phase_currents(i_ab, np.array([[0.0, 0.6]]))
    i_s = -0.5 * out[0, 0] + 0.5 * np.sqrt(3) * out[0, 1]
    np.testing.assert_allclose(out[0, 0], a, atol=1e-12)  # i_r not delayed
    np.testing.assert_allclose(i_s, fractional_delay(phases[None, None, :, 1], np.array([0.6]))[0, 0], atol=1e-12)


def test_a_set_read_with_a_sequence_is_written_back_as_what_was_read(card_record, tmp_path):
    """The voltages are realigned on reading; written back, the set keeps its phase currents and
    their skews, and states no voltage skew (reading it again must not realign twice)."""
    from benchmark.problems.timedomain.data import write_startup_dataset

    kind, made, folder = card_record
    _state(folder, {"i_r": 0.0, "v_r": 0.2, "v_s": 0.4, "i_s": 0.6, "v_t": 0.8} if kind == "dol"
           else {"i_r": 0.0, "i_s": 0.6})
    first = load_startup_dataset(folder)
    again = load_startup_dataset(write_startup_dataset(tmp_path / "copy", first))
    assert again.channel_skew == {"i_r": 0.0, "i_s": 0.6}
    a, b = first.startups[0], again.startups[0]
    for name in ("v_alpha", "v_beta", "i_alpha", "i_beta"):
        np.testing.assert_allclose(getattr(b, name), getattr(a, name), rtol=1e-12, atol=1e-9)

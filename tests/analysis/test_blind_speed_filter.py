"""A blind set's speed channel: its filter stated in meta.yaml, healthy channels filtered too."""

from __future__ import annotations


def test_a_blind_set_states_its_speed_filter_and_healthy_channels_carry_one_too(tmp_path):
    """``speed_filter`` (meta.yaml) is a fact of the instrument: a plant set whose tachometer
    effect has a filter states its time constant, an encoder's half its gate time; of the sets
    without a tachometer effect about :data:`STATED_FILTER_WITHOUT` have an RC filter of the
    plant's own on their speed, stated the same way (so that a statement says nothing of the
    truth); motulator's speed sensor gets the same RC filter, before the acquisition's noise, and
    noise of its own that the filter colours (0.5-2 times the white), none where unfiltered."""
    from pathlib import Path

    from hydra import compose, initialize_config_dir

    from benchmark.analysis.blind import BlindSettings
    from benchmark.analysis.blind_sources import SOURCES, STATED_FILTER_WITHOUT

    conf = str(Path(__file__).resolve().parents[2] / "conf")
    with initialize_config_dir(version_base="1.3", config_dir=conf):
        s = BlindSettings.from_run(compose("blind", overrides=["source=plant", "n=60", "seed=5", "forms=heldout",
                                                               "only_effects=[speed_sensor_gain,two_mass]"]))
    draws, _ = SOURCES["plant"](s)
    tach = [d for d in draws if "speed_sensor_gain" in d["effects"] and d["spec"]["sensors"]["has_speed"]]
    gates = [next(e["gate_time"] for e in d["spec"]["effects"] if e["name"] == "speed_sensor_gain") for d in tach]
    assert tach and all(d["speed_filter"] == 0.5 * g for d, g in zip(tach, gates, strict=True))
    healthy = [d for d in draws if "speed_sensor_gain" not in d["effects"] and d["spec"]["sensors"]["has_speed"]]
    stated = [d for d in healthy if d["speed_filter"] is not None]
    assert all(1e-3 <= d["speed_filter"] <= 5e-3 and d["spec"]["sensors"]["speed_lag"] == d["speed_filter"]
               for d in stated)
    assert all("speed_lag" not in d["spec"]["sensors"] for d in healthy if d["speed_filter"] is None)
    assert abs(len(stated) / len(healthy) - STATED_FILTER_WITHOUT) < 0.2, (len(stated), len(healthy))

    with initialize_config_dir(version_base="1.3", config_dir=conf):
        m = BlindSettings.from_run(compose("blind", overrides=["source=motulator", "n=30", "seed=5"]))
    mdraws, _ = SOURCES["motulator"](m)
    assert all(d["noise"].get("speed_filter") == d["speed_filter"] for d in mdraws)
    assert 0 < sum(d["speed_filter"] is not None for d in mdraws) < len(mdraws)
    for d in mdraws:
        ratio = d["noise"].get("speed_coloured_std", 0.0) / d["noise"]["speed_std"]
        assert (0.5 <= ratio <= 2.0) if d["speed_filter"] else ratio == 0.0

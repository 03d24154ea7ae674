"""The motor zoo: coverage, sources, referral and per-motor settings."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml

from synthetic import zoo


@pytest.fixture(scope="module")
def motors():
    return zoo.load_zoo()


@pytest.fixture(scope="module")
def entries():
    return {e["name"]: e for e in yaml.safe_load(zoo.ZOO_FILE.read_text())["motors"]}


def test_size_power_span_and_pole_pairs(motors):
    assert len(motors) >= 24
    assert len({m.name for m in motors}) == len(motors)
    kw = [m.rated_power / 1e3 for m in motors]
    # issue 14 asks for 0.37 to 200 kW: the zoo reaches 200 kW (Krause's 500 hp machine, 373 kW);
    # its smallest published motor is Alonge's 1 kW one (no citable set below that yet).
    assert min(kw) <= 1.0 and max(kw) >= 200.0
    assert all(0.37 <= k <= 400.0 for k in kw)
    assert {m.pole_pairs for m in motors} == {1, 2, 3, 4}


def test_every_motor_cites_a_source(motors, entries):
    for m in motors:
        assert m.source and len(m.source) > 30, m.name
        assert entries[m.name]["source"].strip() == m.source, m.name


def test_referred_parameters_are_physical_and_match_the_file(motors, entries):
    for m in motors:
        p = zoo.project_parameters(m)
        assert all(p[k] > 0 for k in ("Rs", "Ls", "Le", "Rr", "J")), m.name
        assert p["fv"] >= 0 and p["fc"] >= 0 and p["Le"] < p["Ls"], m.name
        assert p == pytest.approx(entries[m.name]["referred"], rel=1e-6), m.name


def test_referral_keeps_stator_side_invariants(motors):
    for m in motors:
        p = zoo.project_parameters(m)
        Ls, Lr = m.Lls + m.Lm, m.Llr + m.Lm
        assert p["Ls"] == pytest.approx(Ls)
        assert p["Le"] == pytest.approx((1 - m.Lm**2 / (Ls * Lr)) * Ls)  # sigma*Ls
        assert p["Ls"] / p["Rr"] == pytest.approx(Lr / m.Rr)  # rotor time constant


def test_inductances_come_from_the_published_reactances(entries):
    for e in entries.values():
        if "reactances" not in e:
            continue
        w = 2 * math.pi * e["frequency"]
        for x, lk in (("Xls", "Lls"), ("Xlr", "Llr"), ("Xm", "Lm")):
            assert e[lk] == pytest.approx(e["reactances"][x] / w, rel=1e-6), e["name"]


def test_rules_fill_only_what_is_missing(motors, entries):
    for m in motors:
        e = entries[m.name]
        assert set(m.derived) == {k for k in ("J", "fv", "fc") if e.get(k) is None}, m.name
        if "J" in m.derived:
            assert m.J == pytest.approx(zoo.inertia_rule(zoo.rated_torque(m)))
        if "fv" in m.derived:
            w = zoo.rated_speed(m)
            assert m.fv * w**2 + m.fc * w == pytest.approx(zoo.FRICTION_LOSS_FRACTION * m.rated_power)


def test_recommended_settings(motors):
    for m in motors:
        r = zoo.recommended_settings(m)
        assert 5000 <= r["sample_rate"] <= 20000 and 0 < r["duration"] <= 5.0, m.name
        assert r["duration"] >= 1.5 * m.J * zoo.synchronous_speed(m) / zoo.rated_torque(m) or r["duration"] == 5.0
        level = r["noise"]["current_std"] / (math.sqrt(2) * zoo.rated_current(m))
        assert 0.002 <= level <= 0.005, m.name


def test_zoo_dataset_from_motulator(tmp_path, motors):
    pytest.importorskip("motulator")
    m = zoo.get_motor("motulator_2p2kw")
    truth = zoo.make_zoo_dataset(m, "dol", None, 3, tmp_path, duration=0.05, sample_rate=5000)
    assert truth["parameters"] == pytest.approx(zoo.project_parameters(m))
    assert truth["noise"] == pytest.approx(zoo.recommended_settings(m)["noise"])
    d = np.genfromtxt(tmp_path / "startup.csv", delimiter=",", names=True)
    assert len(d) == 251 and (tmp_path / "meta.yaml").exists()


def test_noise_settings_of_both_sources():
    m = zoo.get_motor("krause_500hp")
    i_peak = math.sqrt(2) * zoo.rated_current(m)
    for kind in ("white", "coloured"):
        ind, mot = zoo.independent_noise(m, kind), zoo.motulator_noise(m, kind)
        assert ind["current_white"] == pytest.approx(mot["current_std"]) == pytest.approx(0.003 * i_peak)
        assert ind["speed_quantum"] == pytest.approx(mot["speed_quantum"])
    white, coloured = zoo.motulator_noise(m, "white"), zoo.motulator_noise(m, "coloured")
    assert "current_colored_std" not in white and coloured["current_colored_std"] == pytest.approx(0.003 * i_peak)
    fs = zoo.recommended_settings(m)["sample_rate"]  # the AR(1) pole per sample of independent_noise
    assert math.exp(-2 * math.pi * coloured["current_colored_bandwidth"] / fs) == pytest.approx(0.95)
    assert zoo.motulator_noise(m, "none") == {}
    with pytest.raises(ValueError, match="noise kind"):
        zoo.motulator_noise(m, "pink")


def test_unknown_motor_and_source():
    with pytest.raises(KeyError, match="no zoo motor"):
        zoo.get_motor("perpetuum_mobile")
    with pytest.raises(ValueError, match="source"):
        zoo.make_zoo_dataset("alonge_1kw", source="matlab")


def test_independent_source_simulates_a_zoo_motor_with_its_referred_truth(tmp_path):
    """The independent plant now takes any zoo motor (tests/studies/test_zoo.py checks the
    adapter in detail): the truth it writes is the zoo's referred parameter set."""
    import yaml

    zoo.make_zoo_dataset("alonge_1kw", out=tmp_path, source="independent", duration=0.3)
    truth = yaml.safe_load((tmp_path / "truth.yaml").read_text())
    want = zoo.project_parameters(zoo.get_motor("alonge_1kw"))
    for k in ("Rs", "Ls", "Le", "Rr", "J"):
        assert truth["parameters"][k] == pytest.approx(want[k], rel=1e-9), k

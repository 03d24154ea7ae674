"""Held-out forms of the motulator source: the split, the draws, the curves and the records.

motulator injects three effects; their held-out forms (gap plus M800-50A magnetising curve,
slip clutch, battery charger; the retired elastomer coupling, DC generator and eddy-current brake
loads are drawn by name only) are built
on motulator's own classes (``synthetic/motulator_effects.py``). Records: a 2-pole 1 kW motor,
0.08 s at 5 kHz, noise-free.
"""

from __future__ import annotations

import numpy as np
import pytest

from synthetic.independent.forms import MOTULATOR_DEVELOPMENT, MOTULATOR_HELDOUT, MOTULATOR_RETIRED, motulator_forms_of
from synthetic.motulator_effects import EFFECTS, steel_gap_inductance
from tests.synthetic.test_motulator_source import PAR  # motulator's small 2-pole motor
from tests.synthetic.test_motulator_source import SMALL as MOTULATOR_SMALL

SMALL = {**MOTULATOR_SMALL, "rated_power": 1000.0}  #: with a rating (the held-out forms size by its torque)
HELD = {"main_saturation": {"form": "steel_gap", "size": 0.3, "iron_ratio": 250.0},
        "two_mass": {"form": "slip_clutch", "size": 0.4, "resonance_hz": 30.0, "damping_ratio": 0.1, "slip_share": 0.8},
        "load_torque": {"form": "battery_charger", "size": 0.5, "time": 0.0, "cut_in_ratio": 0.2}}


def _csv(path):
    d = np.genfromtxt(path, delimiter=",", names=True)
    return {n: d[n] for n in d.dtype.names}


def test_the_split_covers_motulators_effects_and_the_draws_keep_development_by_default():
    from benchmark.analysis.blind_sources import MOTULATOR_EFFECTS, motulator_options

    assert set(MOTULATOR_DEVELOPMENT) == set(MOTULATOR_HELDOUT) == set(EFFECTS) == set(MOTULATOR_EFFECTS)
    for name in EFFECTS:
        assert not set(MOTULATOR_DEVELOPMENT[name]) & set(MOTULATOR_HELDOUT[name])
        assert motulator_forms_of(name, "all") == (MOTULATOR_DEVELOPMENT[name] + MOTULATOR_RETIRED.get(name, ())
                                                   + MOTULATOR_HELDOUT[name])
        assert not set(MOTULATOR_RETIRED.get(name, ())) & set(motulator_forms_of(name, "heldout"))
    rng = np.random.default_rng(2)
    dev = [motulator_options(rng, e, "development", 0.6) for e in EFFECTS for _ in range(20)]
    assert all("form" not in o or o["form"] in ("step", "constant", "quadratic") for o in dev)
    assert {o.get("exponent") for o in dev[:20]} <= {2.0, 4.0, 6.0, 7.0}
    held = {e: {motulator_options(rng, e, "heldout", 0.6)["form"] for _ in range(10)} for e in EFFECTS}
    assert held == {e: set(MOTULATOR_HELDOUT[e]) for e in EFFECTS}


def test_steel_gap_inductance_meets_motulators_size_convention():
    Ls, psi_n = PAR["Ls"], 0.75
    for size, x in ((0.15, 500.0), (0.5, 150.0)):
        L, curve = steel_gap_inductance(Ls, psi_n, size, x)
        psi = np.linspace(1e-3, 1.3, 2000)
        Lpsi = L(psi)
        assert float(L(psi_n)) == pytest.approx(Ls, rel=0.01)
        assert Lpsi.max() == pytest.approx((1 + size) * Ls, rel=1e-3)
        assert np.all(np.diff(Lpsi[psi > psi_n]) < 0)  # saturating beyond the rated flux
        i = psi / Lpsi
        assert np.all(np.diff(i) > 0)  # the current rises with the flux: a monotone curve
        assert 1.4 < psi_n * 1.8 / curve.table[1][-1] < 1.8  # the rated flux density of the steel, T


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    pytest.importorskip("motulator")
    from synthetic.motulator_source import make_motulator_dataset

    out = {}
    retired = {"elastomer": {"two_mass": {"form": "elastomer", "size": 0.4, "resonance_hz": 30.0, "damping_ratio": 0.1,
                                          "hardening": 2.5}},
               "spring": {"two_mass": {"size": 0.4, "resonance_hz": 30.0, "damping_ratio": 0.1}},
               "dc_generator": {"load_torque": {"form": "dc_generator", "size": 0.5, "time": 0.04,
                                                "armature_time_constant": 0.01}},
               "eddy_brake": {"load_torque": {"form": "eddy_brake", "size": 0.5, "time": 0.04,
                                              "critical_speed_ratio": 0.5, "field_time_constant": 0.01}}}
    for name, effects in {"none": None, **{k: {k: v} for k, v in HELD.items()}, **retired}.items():
        folder = tmp_path_factory.mktemp(name)
        stop = name in ("none", "load_torque", "dc_generator", "eddy_brake")
        truth = make_motulator_dataset(SMALL, "dol", effects, None, 0, folder, duration=0.08, sample_rate=5000,
                                       stop=stop, stop_max_duration=0.3)
        out[name] = (_csv(folder / "startup.csv"), _csv(folder / "stop.csv") if stop else None, truth)
    return out


def test_each_heldout_form_changes_motulators_record(records):
    base = records["none"][0]
    for name in HELD:
        rec, _, truth = records[name]
        eff = truth["effects"][0]
        assert eff["form_set"] == "heldout" and eff["form"]["form"] == HELD[name]["form"]
        di = np.sqrt(np.mean((rec["i_r"] - base["i_r"]) ** 2))
        dw = np.sqrt(np.mean((rec["speed"] - base["speed"]) ** 2))
        assert di > 0.05 or dw > 0.5, (name, di, dw)  # > 5 x the blind draws' smallest noise


def test_battery_charger_brakes_above_its_cut_in_speed_only(records):
    """Connected from the start: the speed follows the bare machine's until it passes the cut-in
    speed (a fifth of synchronous: the short record reaches 0.4 of it), then falls behind; in the
    stop it brakes towards that speed."""
    (base, base_stop, _), (rec, stop, truth) = records["none"], records["load_torque"]
    c = truth["effects"][0]["form"]["charger"]
    w_sync = 2 * np.pi * 50
    assert c["w_c"] == pytest.approx(0.2 * w_sync) and c["T_L"] == pytest.approx(0.5 * 1000.0 / (0.97 * w_sync))
    below = np.abs(base["speed"]) < 0.95 * c["w_c"]
    below[np.argmax(~below):] = False  # up to the first pass of the cut-in speed
    assert below.sum() > 10
    np.testing.assert_allclose(rec["speed"][below], base["speed"][below], rtol=0, atol=1e-3)
    assert rec["speed"][-1] < base["speed"][-1] - 1.0
    k = min(len(stop["speed"]), len(base_stop["speed"])) - 1
    assert stop["speed"][k] < base_stop["speed"][k] - 20.0  # it brakes in the free stop
    assert stop["speed"][k] > c["w_c"]  # ... but never below its cut-in speed (0.46 s time constant)


def test_retired_eddy_brake_is_silent_until_excited_and_then_brakes_by_its_law(records):
    """The retired eddy-current brake, drawn by name."""
    (base, base_stop, _), (rec, stop, truth) = records["none"], records["eddy_brake"]
    b = truth["effects"][0]["form"]["brake"]
    before = rec["t"] < b["time"]
    np.testing.assert_allclose(rec["speed"][before], base["speed"][before], rtol=0, atol=1e-3)
    assert rec["speed"][-1] < base["speed"][-1] - 1.0
    w_sync = 2 * np.pi * 50
    q = w_sync / b["w_k"]
    assert b["w_k"] == pytest.approx(0.5 * w_sync) and b["tau_f"] == 0.01
    assert b["T_k"] * 2 * q / (1 + q * q) == pytest.approx(0.5 * 1000.0 / (0.97 * w_sync))  # its size
    k = min(len(stop["speed"]), len(base_stop["speed"])) - 1
    assert stop["speed"][k] < base_stop["speed"][k] - 20.0  # it keeps braking in the free stop


def test_dc_generator_load_is_silent_until_switched_and_then_brakes(records):
    """The retired DC generator form, drawn by name."""
    (base, base_stop, _), (rec, stop, truth) = records["none"], records["dc_generator"]
    g = truth["effects"][0]["form"]["generator"]
    before = rec["t"] < g["time"]
    np.testing.assert_allclose(rec["speed"][before], base["speed"][before], rtol=0, atol=1e-3)
    assert rec["speed"][-1] < base["speed"][-1] - 1.0
    assert g["L_a"] / g["R_a"] == pytest.approx(0.01)
    w_sync = 2 * np.pi * 50
    assert g["k_e"] ** 2 * w_sync / g["R_a"] == pytest.approx(0.5 * 1000.0 / (0.97 * w_sync))  # its size
    k = min(len(stop["speed"]), len(base_stop["speed"])) - 1
    assert stop["speed"][k] < base_stop["speed"][k] - 20.0  # it keeps braking in the free stop


def test_slip_clutch_holds_the_spring_at_its_limit_and_the_retired_elastomer_is_drawn_by_name(records):
    """The slip hub (0.8 of the rated torque) slips in the start: the load-side speed falls behind
    the linear spring's of the same resonance by more than the mechanics' own oscillation; the
    retired elastomer form is still made (by name), labelled a development form."""
    rec, _, truth = records["two_mass"]
    form = truth["effects"][0]["form"]
    assert form["T_lim"] == pytest.approx(0.8 * 1000.0 / (0.97 * 2 * np.pi * 50), rel=1e-12)
    spring = records["spring"][0]
    lag = spring["speed"] - rec["speed"]
    assert lag.max() > 5.0
    _, _, el = records["elastomer"]
    assert el["effects"][0]["form"]["form"] == "elastomer" and "form_set" not in el["effects"][0]

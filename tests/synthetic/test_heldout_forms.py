"""Held-out (second physical) forms of the independent plant: the split, the draws, and the forms'
physics without a simulation (curves, rotor, inverter, filters, probes). Each form on a record:
``test_heldout_forms_on_records.py``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import group_delay

from synthetic.independent import EFFECTS, draw_blind_set, make_spec
from synthetic.independent.curves import M400_50A, LeakageCurve, MagnetisingCurve
from synthetic.independent.forms import DEVELOPMENT, HELDOUT, RETIRED, SCENARIOS, forms_of
from synthetic.independent.probes import current_transformer, hall_core
from synthetic.independent.rotor import design
from tests.synthetic.heldout_records import (
    EFFECT_OF,
    FS,
    IN,
    MID,
    MO,
    MOTOR,
    NOISE,
    base,
    held,
    phase_ab,
    record,
)


# --- the split and the draws ---------------------------------------------------------------
def test_every_effect_has_a_heldout_form_and_development_is_what_the_diagnosis_saw():
    seen = {"coulomb_friction": ("coulomb",), "double_cage": ("double_cage", "deep_bar"),
            "main_saturation": ("frohlich", "arctan", "table"), "iron_loss": ("eddy_winding", "shunt"),
            "leakage_saturation": ("lorentzian", "frohlich"), "load_torque": ("constant", "quadratic", "step"),
            "two_mass": ("spring", "backlash"), "temperature_drift": ("one_body", "two_body"),
            "inverter_drop": ("igbt", "mosfet"), "current_sensor_saturation": ("tanh", "knee", "clip"),
            "speed_sensor_gain": ("gain", "gain_ripple"), "sensor_offset": ("both", "current", "voltage"),
            "channel_delay": ("current_lag", "voltage_lag")}
    assert DEVELOPMENT == seen and set(HELDOUT) == set(EFFECTS) == set(seen)
    # held out until developed on
    assert RETIRED == {"speed_sensor_gain": ("tacho_filter",), "two_mass": ("elastomer",),
                       "channel_delay": ("mux_skew",), "load_torque": ("dc_generator", "eddy_brake")}
    for name, forms in RETIRED.items():
        assert not set(forms) & set(HELDOUT[name]) and not set(forms) & set(seen[name]), name
    for name, forms in HELDOUT.items():
        assert forms and not set(forms) & set(seen[name]), name
        assert set(forms) <= set(MID), name  # every held-out form is exercised below
    assert forms_of("current_sensor_saturation", "heldout", "pwm") == ("hall_core",)
    assert set(SCENARIOS) <= set(EFFECT_OF)


def test_draws_take_development_forms_unless_told_and_respect_the_scenario():
    rng = np.random.default_rng(1)
    for name, eff in EFFECTS.items():
        dev = {eff.random_form(rng) for _ in range(40)}
        held_forms = {eff.random_form(rng, "heldout", "pwm") for _ in range(40)}
        assert dev == set(DEVELOPMENT[name]), name
        assert held_forms == set(HELDOUT[name]) - {"current_transformer"}, name
    a = draw_blind_set(np.random.default_rng(11), n_effects=3)
    assert a == draw_blind_set(np.random.default_rng(11), n_effects=3, forms="development")
    assert all(e["form"] in DEVELOPMENT[e["name"]] for e in a["effects"])
    spec = draw_blind_set(np.random.default_rng(3), effects=list(EFFECTS)[:9], scenario="pwm", forms="heldout")
    assert spec == draw_blind_set(np.random.default_rng(3), effects=list(EFFECTS)[:9], scenario="pwm", forms="heldout")
    assert all(e["form"] in HELDOUT[e["name"]] for e in spec["effects"])
    for scenario in ("dol", "six_step", "pwm"):
        specs = [make_spec(MOTOR, scenario, list(EFFECTS)[9:], seed=s, form_set="heldout") for s in range(30)]
        got = {e["form"] for sp in specs for e in sp["effects"]}
        ok = {f for name in list(EFFECTS)[9:] for f in HELDOUT[name] if scenario in SCENARIOS.get(f, (scenario,))}
        assert got == ok, scenario
    with pytest.raises(ValueError, match="current_transformer.*only in"):
        make_spec(MOTOR, "pwm", ["current_sensor_saturation"], forms={"current_sensor_saturation":
                                                                        "current_transformer"})
    with pytest.raises(ValueError, match="forms must be one of"):
        make_spec(MOTOR, "dol", ["iron_loss"], form_set="secret")


# --- curves, rotor, inverter, filters and probes without a simulation -------------------------
def test_heldout_magnetising_curves_are_monotone_with_the_asked_drop_and_slope_at_zero():
    i = np.linspace(1e-3, 60.0, 6001)
    for form in ("langevin", "steel_gap"):
        for drop in (0.08, 0.3):
            c = (MagnetisingCurve.steel_gap(0.2, 0.8, drop, 180.0) if form == "steel_gap"
                 else MagnetisingCurve.with_drop(form, 0.2, 0.8, drop))
            f = c.flux(i)
            slope = np.diff(f) / np.diff(i)
            assert np.all(slope > 0) and slope[0] == pytest.approx(0.2, rel=1e-3), form
            assert 0.8 / np.interp(0.8, f, i) == pytest.approx(0.2 * (1 - drop), rel=3e-3), form
            assert slope[-1] < 0.1 * 0.2  # deep saturation: towards the air-path slope
    x = np.array([0.5, 2.0, 10.0])
    lv = MagnetisingCurve("langevin", 1.0, 1.0, 0.0 + 1e-9)
    np.testing.assert_allclose(lv.flux(x), 3 * (1 / np.tanh(x) - 1 / x), rtol=1e-6)  # M = M_s L(H/a)
    # the steel's rated flux density: the iron path over the gap sets it, within the table
    c = MagnetisingCurve.steel_gap(0.2, 0.8, 0.19, 180.0)
    B_ref = 0.8 * M400_50A[-1, 0] / c.table[1][-1]
    assert 1.3 < B_ref < 1.7
    with pytest.raises(ValueError, match="beyond the steel"):
        MagnetisingCurve.steel_gap(0.2, 0.8, 0.6, 10.0)  # a short iron path cannot saturate that much


def test_closed_slot_bridge_saturates_early_and_keeps_the_rated_current_leakage():
    bridge = LeakageCurve("bridge", 1e-3, 2e-3, 1.0)
    r = np.array([0.5, 1.0, 3.0, 10.0, 100.0])
    flux = bridge.inductance(r) * r
    np.testing.assert_allclose(flux, 1e-3 * r + 2e-3 * np.tanh(r), rtol=1e-12)  # flux limited to L_sat i_k
    assert bridge.monotone()
    ds = held("closed_slot_bridge")
    eff = ds.truth["effects"][0]
    cage = ds.plant.cage()
    lo, hi = 0.9 * IN, 6 * IN
    L_lo, L_hi = (cage.low_slip()[1] - cage.common.L0 + float(cage.common.inductance(i)[0]) for i in (lo, hi))
    assert L_lo == pytest.approx(MO.machine.Llr, rel=1e-9)  # the locked-rotor test at rated current
    assert L_hi / L_lo == pytest.approx(MID["closed_slot_bridge"]["size"], rel=1e-9) == eff["achieved_size"]
    assert eff["rotor_leakage_unsaturated"] > 1.5 * MO.machine.Llr  # the unsaturated bridge adds leakage
    # less leakage at the starting current: a higher start current (this motor's 5 ohm stator holds it)
    assert np.max(np.hypot(*phase_ab(ds.startup, "i"))) > 1.015 * np.max(np.hypot(*phase_ab(base().startup, "i")))


def test_tapered_bar_gives_the_asked_resistance_ratio_and_a_faster_start():
    m = MO.machine
    for taper in (0.4, 2.5):
        cage, ratio = design("tapered_bar", m.Rr, m.Llr, 2 * math.pi * 50, 1.25, n=6, taper=taper)
        assert ratio == pytest.approx(1.25, rel=1e-6)
        assert cage.low_slip()[0] == pytest.approx(m.Rr, rel=1e-9)
        widths = 1 / np.asarray(cage.R) * cage.R[0]  # slice widths from their resistances
        assert widths[-1] == pytest.approx(taper, rel=1e-9)
    ds = held("tapered_bar")
    assert ds.truth["effects"][0]["achieved_size"] == pytest.approx(1.4, rel=1e-6)
    assert ds.startup["speed"][1000] > 1.02 * base().startup["speed"][1000]


def test_capacitive_dead_time_error_grows_smoothly_through_zero_current():
    from synthetic.independent.inverter import Inverter, applied_voltage

    Ed, td, h, i_c = 300.0, 3e-6, 1e-5, 0.4
    prm = Inverter(dead_time=td, i_transition=i_c).pack(Ed)
    u, nf = np.array([1.0, 0.0, 0.0]), np.zeros(3)
    nr = np.array([1.0, 0.0, 0.0])  # phase R's gate rises in this step

    def loss(i_r):  # volt-seconds lost by phase R at its rising edge, current i_r out of the leg
        va = applied_voltage(u, nr, nf, i_r, 0.0, prm, h)[0]
        vb = applied_voltage(u, np.zeros(3), nf, i_r, 0.0, prm, h)[0]
        return (vb - va) * h * 1.5  # alpha = 2/3 (v_R - ...)

    for i_r, share in ((1.0, 1.0), (0.0, 1.0), (-0.2, 0.75), (-0.4, 0.5), (-1.6, 0.125)):
        assert loss(i_r) == pytest.approx(Ed * td * share, rel=1e-9), i_r  # Ed t_d g(i)
    dev = record(["inverter_drop"], "pwm", {"inverter_drop": "mosfet"},
                  {"inverter_drop": {k: MID["mosfet_capacitive"][k] for k in ("size", "r", "dead_time")}})
    diff = np.sqrt(np.mean((held("mosfet_capacitive").startup["i_r"] - dev.startup["i_r"]) ** 2))
    assert diff > 3 * NOISE["current_white"]  # a different form at the same size, not a relabelling


def test_bessel_anti_aliasing_delays_the_currents_by_its_design_group_delay():
    from scipy.signal import bessel, bilinear

    h, tau = 1 / (8 * FS), 1.25 / FS
    b, a = bilinear(*bessel(2, 1 / tau, analog=True, norm="delay"), fs=1 / h)
    w, gd = group_delay((b, a), w=[2 * math.pi * 50 * h, 2 * math.pi * 500 * h])
    np.testing.assert_allclose(gd * h, tau, rtol=0.01)
    ds, ref = held("anti_alias"), base()
    t = ref.startup["t"]
    for ch in ("i_r", "i_s"):
        lagged = np.interp(t - tau, t, ref.startup[ch])
        assert np.max(np.abs(ds.startup[ch] - lagged)[200:]) < 0.02 * np.max(np.abs(ref.startup[ch]))
    np.testing.assert_array_equal(ds.startup["v_r"], ref.startup["v_r"])


def test_probes_compress_by_their_core_and_remember_it():
    L = 10.0
    t = np.arange(0, 0.2, 1e-4)
    up_down = np.concatenate([np.linspace(0, 30, 500), np.linspace(30, 0, 500)])[:, None]
    r = hall_core(up_down, L, 8.0, 0.05)[:, 0]
    assert np.all(np.diff(r[:500]) >= 0) and r[499] < 30 and r[499] > L  # soft: still rising beyond L
    assert hall_core(np.array([[L * 1.1]]), L, 8.0, 0.0)[0, 0] == pytest.approx(L, rel=1e-9)  # 10 % short at L
    assert r[-1] == pytest.approx(0.05, rel=1e-6)  # back at zero current: the magnetic offset of the overload
    w = 2 * math.pi * 50
    small = (0.3 * L * np.sin(w * t))[:, None]  # its flux starts at zero: a DC part of one amplitude
    ct = current_transformer(np.repeat(small, 2, axis=1), 1e-4, L, w, 12.0, 1.5, [0.0, 0.0])
    assert np.max(np.abs(ct[:, 0] - small[:, 0])) < 0.01 * 0.3 * L  # below the knee: a good CT
    offset = (2 * L * (np.exp(-t / 0.03) - np.cos(w * t)))[:, None]  # a fully offset start current
    sat = current_transformer(np.repeat(offset, 2, axis=1), 1e-4, L, w, 12.0, 1.5, [0.5, -0.5])
    assert np.max(np.abs(sat[:, 0] - offset[:, 0])) > 0.3 * L  # the DC offset saturates the core
    assert np.max(np.abs(sat[:, 0] - sat[:, 1])) > 0.1 * L  # remanence of either sign: different readings
    ds, ref = held("current_transformer"), base()
    assert np.max(np.abs(ds.startup["i_r"][-1000:] - ref.startup["i_r"][-1000:])) < 0.02 * IN

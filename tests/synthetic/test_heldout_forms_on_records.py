"""Held-out (second physical) forms of the independent plant on a record: each changes it measurably
at a mid-realistic size and stays finite, and each behaves as its physics says (loads, iron losses,
friction, heating, sensors, saturation, couplings); records reproducible per seed. The split, the
draws and the forms without a simulation: ``test_heldout_forms.py``."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from synthetic.independent import make_dataset, make_spec
from tests.synthetic.heldout_records import (
    FS,
    MID,
    MO,
    MOTOR,
    NOISE,
    SCENARIO_OF,
    SLOW,
    base,
    held,
    phase_ab,
    record,
)


@pytest.mark.parametrize("form", sorted(MID))
def test_every_heldout_form_changes_the_record_measurably_and_stays_finite(form):
    ds, ref = held(form), base(SCENARIO_OF.get(form, "dol"))
    assert ds.truth["simulation"]["unconverged_solves"] == 0
    assert ds.truth["effects"][0]["form"] == form
    assert all(np.all(np.isfinite(v)) for v in ds.startup.values())
    change = {ch: np.sqrt(np.mean((ds.startup[ch] - ref.startup[ch]) ** 2)) / NOISE[noise]
              for ch, noise in (("i_r", "current_white"), ("i_s", "current_white"), ("speed", "speed_white"))}
    change["stop"] = np.sqrt(np.mean((ds.stop["speed"] - ref.stop["speed"]) ** 2)) / NOISE["speed_white"]
    assert max(change.values()) > 5, change  # several times a moderate bench's noise


def test_dc_generator_torque_follows_its_armature_circuit():
    ds = held("dc_generator")
    eff = ds.truth["effects"][0]
    t, w, tq = ds.startup["t"], ds.startup["speed"], ds.startup["torque"]
    on = t >= eff["t_step"]
    assert np.all(tq[~on] == 0.0)  # an open armature: no torque, whatever the speed
    ke, R, La = eff["emf_constant"], eff["armature_resistance"], eff["armature_inductance"]
    ia, out = 0.0, []  # the armature circuit on the recorded speed, implicit Euler per sample
    for wk in w[on]:
        out.append(ia)
        ia = (ia + (ke * wk - MID["dc_generator"]["brush_drop"] * np.tanh(ia / (0.01 * eff["load_torque"] / ke)))
              / FS / La) / (1 + R / (La * FS))
    expected = ke * np.array(out)
    tau = La / R
    assert tau == pytest.approx(6e-3)
    k = int(round(tau * FS))
    assert tq[on][k] == pytest.approx((1 - math.exp(-1)) * ke**2 * w[on][k] / R, rel=0.05)  # one time constant
    assert np.max(np.abs(tq[on] - expected)) < 0.03 * np.max(expected)
    assert ds.stop["speed"][-1] < 0.5 * base().stop["speed"][-1]  # it keeps braking in the free stop
    standstill = record(["load_torque"], "dol", {"load_torque": "dc_generator"},
                         {"load_torque": {**MID["dc_generator"], "step_fraction": 0.0}}, duration=0.05, has_torque=True)
    assert standstill.startup["torque"][0] == 0.0 and standstill.startup["torque"][5] < 1e-3 * eff["load_torque"]


def test_eddy_brake_torque_follows_its_law_and_its_excitation():
    """Before the excitation no torque; after it the brake's law at the recorded speed times the
    square of the field current's first-order rise; peak torque ``T_k`` at the critical speed,
    the steady torque at synchronous speed the drawn size; it keeps braking in the free stop."""
    ds = held("eddy_brake")
    eff = ds.truth["effects"][0]
    mid = MID["eddy_brake"]
    t, w, tq = ds.startup["t"], ds.startup["speed"], ds.startup["torque"]
    on = t >= eff["t_step"]
    assert np.all(tq[~on] == 0.0)
    T_k, w_k = eff["peak_torque"], eff["critical_speed"]
    assert w_k == pytest.approx(mid["critical_speed_ratio"] * MO.w_sync)
    q = MO.w_sync / w_k
    assert T_k * 2 * q / (1 + q * q) == pytest.approx(mid["size"] * MO.rated_torque, rel=1e-12)
    field = 1 - np.exp(-(t[on] - eff["t_step"]) / mid["field_time_constant"])
    law = T_k * field**2 * 2 * (w[on] / w_k) / (1 + (w[on] / w_k) ** 2)
    assert np.max(np.abs(tq[on] - law)) < 0.01 * np.max(law)
    assert ds.stop["speed"][-1] < 0.5 * base().stop["speed"][-1]


def test_battery_charger_brakes_only_above_its_cut_in_speed_and_linearly_there():
    """Connected from the start: no torque below the cut-in speed ``w_c`` (the diodes block),
    above it a torque linear in the excess speed reaching the drawn size at synchronous speed;
    in the free stop it brakes until the speed falls to ``w_c``, then the stop is the bare machine's."""
    ds = held("battery_charger")
    eff = ds.truth["effects"][0]
    mid = MID["battery_charger"]
    w_c = eff["cut_in_speed"]
    assert w_c == pytest.approx(mid["cut_in_ratio"] * MO.w_sync) and eff["t_step"] == 0.0
    w, tq = ds.startup["speed"], ds.startup["torque"]
    below, above = np.abs(w) < w_c, np.abs(w) > w_c
    assert below.sum() > 50 and above.sum() > 50  # the start runs through the cut-in speed
    assert np.all(tq[below] == 0.0)
    law = mid["size"] * MO.rated_torque * (np.abs(w[above]) - w_c) / (MO.w_sync - w_c)
    assert np.max(np.abs(tq[above] - law)) < 0.01 * mid["size"] * MO.rated_torque
    stop = ds.stop["speed"]
    assert stop[0] > w_c and stop[-1] < stop[0]
    k = int(np.argmax(stop < w_c))  # where the charger lets go
    assert 0 < k < len(stop) - 10
    fast, slow = (stop[0] - stop[k]) / k, (stop[k] - stop[-1]) / (len(stop) - 1 - k)
    assert fast > 3 * slow  # braked hard above the cut-in speed, coasting on friction below it


def test_steinmetz_iron_loss_separates_into_hysteresis_and_eddy_currents():
    """No-load runs at rated voltage and frequency and at half of both: the iron loss by power
    balance (input less copper losses and shaft power), and the classical two-frequency
    separation (hysteresis ~ f psi^alpha, eddy currents ~ f^2 psi^2, corrected for the air-gap
    flux each run has) gives back the hysteresis share."""
    size, h, alpha = (MID["steinmetz"][k] for k in ("size", "hysteresis_share", "exponent"))
    loss, flux = [], []
    for f in (50.0, 25.0):
        spec = make_spec(MOTOR, "dol", ["iron_loss"], seed=5, duration=0.8, ideal_supply=True, noise={},
                         oversampling=8, sample_rate=SLOW, forms={"iron_loss": "steinmetz"})
        spec["scenario"].update(V=MO.voltage * f / 50.0, f=f)
        spec["effects"][0].update(MID["steinmetz"])
        ds = make_dataset(spec)
        tr, last = ds.trajectory, slice(-8001, -1)  # the last 0.2 s: 10 (resp. 5) whole periods
        col = {c: tr.col(c)[last] for c in ("v_a", "v_b", "i_a", "i_b", "P_s", "P_r", "T_e", "w_m", "psi_a", "psi_b")}
        p_in = 1.5 * (col["v_a"] * col["i_a"] + col["v_b"] * col["i_b"])
        loss.append(np.mean(p_in - col["P_s"] - col["P_r"] - col["T_e"] * col["w_m"]))
        Lls = ds.plant.machine.Lls
        flux.append(np.mean(np.hypot(col["psi_a"] - Lls * col["i_a"], col["psi_b"] - Lls * col["i_b"])))
    assert flux[0] == pytest.approx(MO.psi_rated, rel=0.03)
    assert loss[0] == pytest.approx(size * MO.rated_power * (flux[0] / MO.psi_rated) ** 2, rel=0.03)
    r = flux[1] / flux[0]
    hysteresis = (loss[1] - loss[0] * r**2 / 4) / (r**alpha / 2 - r**2 / 4)
    assert hysteresis / loss[0] == pytest.approx(h, abs=0.04)
    assert loss[1] / loss[0] > 1.3 * r**2 / 4  # far from eddy currents alone


def test_bearing_friction_follows_palmgren_in_the_free_stop():
    ds = held("bearing")
    eff = ds.truth["effects"][0]
    m = ds.plant.machine
    w = ds.stop["speed"]
    dw = np.gradient(w, 1e-3)
    k = slice(200, -200)
    law = -(m.fv * w + eff["size"] + eff["palmgren"] * w ** (2 / 3)) / m.J
    np.testing.assert_allclose(dw[k], law[k], rtol=0.01)
    coulomb = -(m.fv * w + eff["size"]) / m.J
    assert np.mean(np.abs(law[k] - coulomb[k]) / np.abs(coulomb[k])) > 0.2  # not the development form


def test_three_body_heating_sends_the_winding_heat_into_the_core():
    ds = held("three_body")
    eff = ds.truth["effects"][0]
    th = ds.plant.thermal
    traj = ds.trajectory
    K = len(ds.startup["t"]) * 8
    rise_w = traj.col("theta_s")[K] - traj.col("theta_s")[0]
    b = ds.plant.mech_offset() + 5
    core = traj.x[b + 2] - traj.col("theta_s")[0]  # the core's rise at the end of the start-up
    assert eff["achieved_size"] == pytest.approx(MID["three_body"]["size"], rel=0.03)
    E_s = float(np.sum(traj.col("P_s")[:K]) / (8 * FS))
    assert rise_w < 0.99 * E_s / th.C_s  # less than adiabatic: heat left for the core
    assert th.C_s * rise_w + th.C_c * core == pytest.approx(E_s, rel=0.02)  # and none is lost


def test_sensor_forms_on_the_record_match_their_equations():
    from scipy.signal import lsim

    ref = base()
    t, w = ref.startup["t"], ref.startup["speed"]
    # tachometer behind an RC filter: gain times the filtered speed
    tach = held("tacho_filter").startup["speed"]
    filtered = lsim(([1.0], [MID["tacho_filter"]["time_constant"], 1.0]), w, t)[1]
    assert np.max(np.abs(tach - 1.03 * filtered)) < 0.1
    assert np.max(np.abs(tach - 1.03 * w)) > 1.0  # the lag of an accelerating shaft
    # an encoder: gain times the angle turned in the last gate time over that time
    enc = held("encoder_window").startup["speed"]
    gate = MID["encoder_window"]["gate_time"]
    angle = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(t))])
    k = np.flatnonzero(t >= t[0] + gate + 1e-9)
    mean = (angle[k] - np.interp(t[k] - gate, t, angle)) / gate
    assert np.max(np.abs(enc[k] - 1.03 * mean)) < 0.1
    assert np.max(np.abs(enc - 1.03 * w)) > 1.0
    # offsets that drift as each probe warms with its own current
    drift = held("thermal_drift")
    for k, ch in enumerate(("i_r", "i_s")):
        heat = np.array([np.sum(ref.startup[ch][:j + 1] ** 2 * np.exp(-(t[j] - t[:j + 1]) / 1.65)) for j in
                         range(0, len(t), 500)])
        o0, od = MID["thermal_drift"]["current_offsets"][k], MID["thermal_drift"]["drift"][k]
        got = (drift.startup[ch] - ref.startup[ch])[::500]
        np.testing.assert_allclose(got, o0 + od * heat / heat[-1], atol=0.004)
    # a multiplexed card: each channel at its own instant (slot 0.2 samples, order i_r, v_r, i_s)
    mux = held("mux_skew")
    assert mux.truth["effects"][0]["achieved_size"] == pytest.approx(0.25)  # 2 internal steps of 8
    for ch, slot in (("i_r", 0), ("i_s", 2), ("v_r", 1)):
        lagged = np.interp(t - slot * 0.25 / FS, t, ref.startup[ch])
        assert np.max(np.abs(mux.startup[ch] - lagged)[50:]) < 0.01 * np.max(np.abs(ref.startup[ch])), ch


def test_saturation_forms_raise_the_no_load_current_by_their_secant_drop():
    """At no load the stator current is the magnetising current: saturated over unsaturated is
    the curve's secant drop at the air-gap flux the run has (which the curve sets near rated)."""
    runs = {form: record(["main_saturation"], "dol", {"main_saturation": form}, {"main_saturation": MID[form]},
                          duration=0.8, sample_rate=SLOW) for form in ("langevin", "steel_gap")}
    ref = record(duration=0.8, sample_rate=SLOW)
    amp0 = np.hypot(*phase_ab(ref.startup, "i"))[-1000:].mean()
    for form, ds in runs.items():
        tr, Lls = ds.trajectory, ds.plant.machine.Lls
        flux = np.hypot(tr.col("psi_a") - Lls * tr.col("i_a"), tr.col("psi_b") - Lls * tr.col("i_b"))[-8000:].mean()
        curve = ds.plant.mag_curve()
        i_grid = np.linspace(0.0, 40.0, 4001)
        secant = flux / np.interp(flux, curve.flux(i_grid), i_grid) / curve.Lm0
        assert secant < 1 - 0.6 * MID[form]["size"], form  # well into the knee
        ref_flux = np.hypot(*(ref.trajectory.col(f"psi_{c}") - Lls * ref.trajectory.col(f"i_{c}") for c in "ab"))
        amp = np.hypot(*phase_ab(ds.startup, "i"))[-1000:].mean()
        expected = (flux / secant) / ref_flux[-8000:].mean()
        assert amp / amp0 == pytest.approx(expected, rel=0.02), form


def test_elastomer_coupling_hardens_with_the_twist_the_run_up_gives_it():
    """The coupling's torque against its twist (the integral of the two speeds) follows the
    progressive law, stiffens by ``hardening`` at the rated torque, and moves the record away
    from the linear spring of the same small-twist resonance."""
    ds = held("elastomer")
    eff = ds.truth["effects"][0]
    tr, h = ds.trajectory, 1 / (8 * FS)
    dw = tr.col("w_m") - tr.col("w_l")
    z = np.concatenate([[0.0], np.cumsum(0.5 * (dw[1:] + dw[:-1]) * h)])
    k, c, z_r = eff["stiffness"], eff["damping"], eff["twist_ref"]
    law = k * z * (1 + (z / z_r) ** 2 / 3) + c * np.sqrt(1 + (z / z_r) ** 2) * dw
    T_sh = tr.col("T_sh")
    assert np.max(np.abs(T_sh - law)) < 0.01 * np.max(np.abs(T_sh))
    assert np.max(np.abs(z)) > 0.8 * z_r  # the starting torque twists it into the progressive range
    z_n = brentq(lambda x: k * x * (1 + (x / z_r) ** 2 / 3) - MO.rated_torque, 0.0, 1.0)  # twist at rated torque
    assert 1 + (z_n / z_r) ** 2 == pytest.approx(MID["elastomer"]["hardening"], rel=1e-9)  # its stiffness there
    spring = record(["two_mass"], "dol", {"two_mass": "spring"}, {"two_mass": MID["elastomer"]}, stop=2.0)
    assert np.sqrt(np.mean((spring.startup["speed"] - ds.startup["speed"]) ** 2)) > 5 * NOISE["speed_white"]


def test_slip_clutch_limits_the_spring_torque_and_slips_in_the_start():
    """A torque limiter in series with the spring: the spring's torque (the transmitted torque
    less the damper's) never passes the limit, the direct-on-line start drives it there (the hub
    slips), and the record moves away from the linear spring of the same resonance."""
    ds = held("slip_clutch")
    eff = ds.truth["effects"][0]
    tr = ds.trajectory
    T_lim = MID["slip_clutch"]["slip_share"] * MO.rated_torque
    assert eff["slip_torque"] == pytest.approx(T_lim, rel=1e-12)
    spring = tr.col("T_sh") - eff["damping"] * (tr.col("w_m") - tr.col("w_l"))
    assert np.max(np.abs(spring)) <= T_lim * (1 + 1e-9)
    assert np.mean(np.abs(spring) > 0.999 * T_lim) > 0.02  # at the limit (slipping) for a part of the start
    linear = record(["two_mass"], "dol", {"two_mass": "spring"}, {"two_mass": MID["slip_clutch"]}, stop=2.0)
    assert np.sqrt(np.mean((linear.startup["speed"] - ds.startup["speed"]) ** 2)) > 5 * NOISE["speed_white"]


def test_heldout_records_are_reproducible_per_seed(tmp_path):
    effects = ["sensor_offset", "current_sensor_saturation", "temperature_drift"]
    forms = {"sensor_offset": "thermal_drift", "current_sensor_saturation": "hall_core",
             "temperature_drift": "three_body"}
    a, b, c = (record(effects, "dol", forms, duration=0.1, noise=NOISE, seed=s) for s in (3, 3, 4))
    for ch in a.startup:
        np.testing.assert_array_equal(a.startup[ch], b.startup[ch])
    assert not np.array_equal(a.startup["i_r"], c.startup["i_r"])
    assert a.truth["effects"] == b.truth["effects"]


@pytest.mark.parametrize("ratio", [-0.1, 1.0, 1.5])
def test_a_battery_charger_whose_cut_in_is_not_below_synchronous_speed_is_refused(ratio):
    """The charger's torque is linear from its cut-in speed to synchronous speed: a cut-in at or
    above it (or below rest) has no such law, and the plant says so instead of dividing by zero."""
    from synthetic.independent.mechanics import Mechanics

    with pytest.raises(ValueError, match="cut_in_speed must be in"):
        Mechanics(load="battery_charger", load_torque=5.0, w_ref=157.0, cut_in_speed=ratio * 157.0)
    Mechanics(load="battery_charger", load_torque=5.0, w_ref=157.0, cut_in_speed=0.5 * 157.0)  # a real one is kept

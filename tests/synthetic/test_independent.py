"""The independent validation plant (synthetic/independent): isolation, physics, effects, seeds.

Records are short (0.8 s, 10 kHz, 8 internal steps per sample) on the paper's 1-kW motor and
noise-free unless a test is about noise, so that the checks can be tight.
"""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest

import synthetic.independent as ind
from synthetic.independent import get_motor, make_dataset, make_spec, write_dataset
from synthetic.independent.dataset import default_noise
from synthetic.independent.rotor import design

PKG = Path(ind.__file__).parent
MOTOR = "paper_1kw"
FS = 10000.0
LAST = slice(-2000, None)  # the last 0.2 s: steady state


def _spec(effects=(), scenario="dol", duration=0.8, forms=None, sizes=None, noise=None, seed=5, **kw):
    spec = make_spec(MOTOR, scenario, list(effects), seed=seed, duration=duration, ideal_supply=True,
                     noise=noise if noise is not None else {}, oversampling=8, sample_rate=FS, forms=forms, **kw)
    for eff in spec["effects"]:
        eff.update((sizes or {}).get(eff["name"], {}))
    return spec


def _run(*args, **kw):
    return make_dataset(_spec(*args, **kw))


def _alpha_beta(rec, prefix):
    r, s = rec[f"{prefix}_r"], rec[f"{prefix}_s"]
    t = rec[f"{prefix}_t"] if f"{prefix}_t" in rec else -r - s
    return (2 / 3) * (r - 0.5 * (s + t)), (s - t) / math.sqrt(3)


def _amplitude(rec):
    return np.hypot(*_alpha_beta(rec, "i"))


def _power(rec):
    va, vb = _alpha_beta(rec, "v")
    ia, ib = _alpha_beta(rec, "i")
    return 1.5 * (va * ia + vb * ib)


@pytest.fixture(scope="module")
def base():
    return _run()


# --- 1. isolation --------------------------------------------------------------------------
def test_imports_nothing_from_the_project():
    offenders = []
    for path in sorted(PKG.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level > 1:
                    offenders.append(f"{path.name}: relative import beyond the package")
                names = [node.module or ""] if node.level == 0 else []
            else:
                continue
            for name in names:
                top = name.split(".")[0]
                own = name == "synthetic.independent" or name.startswith("synthetic.independent.")
                if top in ("benchmark", "plugins") or (top == "synthetic" and not own):
                    offenders.append(f"{path.name}: imports {name}")
    assert not offenders, offenders


# --- 2. physics --------------------------------------------------------------------------
def test_no_load_steady_state_matches_the_phasor_solution(base):
    mo = get_motor(MOTOR)
    m = mo.machine
    slip = m.friction_slip(mo.phase_peak, mo.frequency)
    w_expected = (1 - slip) * 2 * math.pi * mo.frequency / m.p
    w = base.startup["speed"][LAST].mean()
    assert abs(w - w_expected) < 0.005 * w_expected * slip  # far inside the 0.5 % asked for
    amp = _amplitude(base.startup)[LAST].mean()
    I = m.steady_state(mo.phase_peak, mo.frequency, slip)["I"][0]
    assert abs(amp / I - 1) < 1e-3


def test_referral_agrees_with_the_projects_five_state_model():
    """The plant with Llr != Lls and the project's model (Lr = Ls, referred Rr), integrated
    inline here from its equations, on the same six-step voltages."""
    P = {"Rs": 4.96434, "Ls": 0.1075, "Le": 0.01098, "Rr": 1.55618, "J": 0.00642, "fv": 0.00033, "fc": 0.04297}
    machine = ind.TMachine.from_referred(**P, p=1, leakage_ratio=0.6)
    assert machine.Llr != pytest.approx(machine.Lls)
    assert machine.referred() == pytest.approx(P, rel=1e-12)
    spec = make_spec(MOTOR, "six_step", [], seed=1, duration=0.5, noise={}, sample_rate=12000.0)
    spec["machine"] = {k: getattr(machine, k) for k in ("Rs", "Lls", "Llr", "Lm", "Rr")}
    rec = make_dataset(spec).startup
    va, vb = _alpha_beta(rec, "v")
    ia, ib = _alpha_beta(rec, "i")
    Rs, Ls, Le, Rr, J, fv, fc = (P[k] for k in ("Rs", "Ls", "Le", "Rr", "J", "fv", "fc"))
    p, Lr = 1, Ls
    Lm = math.sqrt(Lr * (Ls - Le))
    a11, a33 = (Rs + (Lm / Lr) ** 2 * Rr) / Le, Rr / Lr
    c1, c2 = 1 / Le, Lm / (Le * Lr)
    a13, a31 = a33 * c2, Rr * Lm / Lr

    def f(x, v):
        i_a, i_b, f_a, f_b, w = x
        tm = 1.5 * p * (Lm / Lr) * (f_a * i_b - f_b * i_a)
        tc = fc * np.sign(w) if w != 0 else float(np.clip(tm, -fc, fc))
        return np.array([-a11 * i_a + a13 * f_a + c2 * w * f_b + c1 * v[0],
                         -a11 * i_b + a13 * f_b - c2 * w * f_a + c1 * v[1],
                         a31 * i_a - a33 * f_a - w * f_b, a31 * i_b - a33 * f_b + w * f_a,
                         -w * fv / J + p / J * (tm - tc)])

    x, h, sim = np.zeros(5), (1 / 12000.0) / 2, [np.zeros(5)]
    for k in range(len(va) - 1):
        v = (va[k], vb[k])
        for _ in range(2):
            k1 = f(x, v)
            k2 = f(x + h / 2 * k1, v)
            k3 = f(x + h / 2 * k2, v)
            k4 = f(x + h * k3, v)
            x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        sim.append(x)
    sim = np.array(sim)
    peak = np.max(np.hypot(ia, ib))
    assert peak > 20
    assert np.max(np.abs(sim[:, 0] - ia)) < 0.005 * peak
    assert np.max(np.abs(sim[:, 1] - ib)) < 0.005 * peak
    assert np.max(np.abs(sim[:, 4] / p - rec["speed"])) < 0.1


def test_double_cage_design_gives_the_asked_resistance_ratio():
    m = get_motor("simulink_7k5").machine
    w = 2 * math.pi * 50
    for kind, target in (("double_cage", 1.8), ("deep_bar", 1.3)):
        cage, ratio = design(kind, m.Rr, m.Llr, w, target, n=4)
        assert ratio == pytest.approx(target, rel=1e-6)
        assert cage.low_slip()[0] == pytest.approx(m.Rr, rel=1e-9)
        assert cage.resistance_ratio(0.01 * w) == pytest.approx(1.0, abs=1e-3)


# --- 3. effects --------------------------------------------------------------------------
def test_double_cage_starts_with_more_torque_and_truth_is_the_low_slip_value(base):
    ds = _run(["double_cage"], forms={"double_cage": "double_cage"}, sizes={"double_cage": {"size": 2.0}})
    eff = ds.truth["effects"][0]
    assert eff["achieved_size"] > 1.5
    R_eq, L_eq = ds.plant.cage().low_slip()
    m = ds.plant.machine
    assert ds.truth["parameters"]["Rr"] == pytest.approx(R_eq * m.Ls / (L_eq + m.Lm), rel=1e-12)
    assert ds.startup["speed"][1000] > base.startup["speed"][1000] * 1.02  # 0.1 s: faster run-up
    assert np.max(_amplitude(ds.startup)) < 0.95 * np.max(_amplitude(base.startup))  # deeper bars, less current
    assert _amplitude(ds.startup)[LAST].mean() == pytest.approx(_amplitude(base.startup)[LAST].mean(), rel=2e-3)


def test_main_saturation_raises_the_no_load_current(base):
    ds = _run(["main_saturation"], sizes={"main_saturation": {"size": 0.2}})
    ratio = _amplitude(ds.startup)[LAST].mean() / _amplitude(base.startup)[LAST].mean()
    assert 1.1 < ratio < 1.4  # magnetising current ~ 1/(1 - 0.2) of the unsaturated one


def test_iron_loss_adds_its_power_at_no_load(base):
    size = 0.04
    ds = _run(["iron_loss"], forms={"iron_loss": "shunt"}, sizes={"iron_loss": {"size": size}})
    extra = _power(ds.startup)[LAST].mean() - _power(base.startup)[LAST].mean()
    assert extra == pytest.approx(size * get_motor(MOTOR).rated_power, rel=0.15)


def test_leakage_saturation_raises_start_current_and_torque(base):
    ds = _run(["leakage_saturation"], sizes={"leakage_saturation": {"size": 0.5}})
    assert np.max(_amplitude(ds.startup)) > 1.03 * np.max(_amplitude(base.startup))
    assert ds.startup["speed"][1000] > 1.05 * base.startup["speed"][1000]


def test_temperature_drift_reaches_its_rise():
    ds = _run(["temperature_drift"], sizes={"temperature_drift": {"size": 15.0}})
    eff = ds.truth["effects"][0]
    assert eff["achieved_size"] == pytest.approx(15.0, rel=0.1)


def test_load_torque_gives_the_analytic_loaded_slip():
    mo = get_motor(MOTOR)
    ds = _run(["load_torque"], forms={"load_torque": "constant"}, sizes={"load_torque": {"size": 0.5}})
    slip = mo.machine.friction_slip(mo.phase_peak, mo.frequency, load=0.5 * mo.rated_torque)
    w = ds.startup["speed"][LAST].mean()
    assert w == pytest.approx((1 - slip) * mo.w_sync, rel=2e-4)


def test_two_mass_rings_at_its_resonance():
    f_res = 120.0
    ds = _run(["two_mass"], forms={"two_mass": "spring"},
              sizes={"two_mass": {"size": f_res, "inertia_ratio": 1.0, "damping_ratio": 0.03}})
    assert ds.truth["parameters"]["J"] == pytest.approx(2 * get_motor(MOTOR).machine.J)
    w = ds.startup["speed"][:4000]
    ripple = w - np.convolve(w, np.ones(25) / 25, mode="same")  # 2.5 ms moving mean removes the run-up
    spec = np.abs(np.fft.rfft(ripple[100:-100] * np.hanning(len(ripple) - 200)))
    freq = np.fft.rfftfreq(len(ripple) - 200, 1 / FS)
    band = (freq > 60) & (freq < 300)
    assert freq[band][np.argmax(spec[band])] == pytest.approx(f_res, rel=0.1)


def test_inverter_drop_leaves_recorded_voltages_and_dissipates_the_device_loss():
    """Recorded voltages are the switch-state ones; the currents change; the applied voltage
    falls short of them by the device drops, whose loss lies between the threshold bounds."""
    from synthetic.independent.integrate import COL

    base6 = _run(scenario="six_step", duration=0.6)
    ds = _run(["inverter_drop"], scenario="six_step", duration=0.6, forms={"inverter_drop": "igbt"})
    for ch in ("v_r", "v_s", "v_t"):
        np.testing.assert_array_equal(ds.startup[ch], base6.startup[ch])
    assert np.max(np.abs(ds.startup["i_r"] - base6.startup["i_r"])) > 0.05 * np.max(np.abs(base6.startup["i_r"][LAST]))
    eff = ds.truth["effects"][0]
    out = ds.trajectory.out[:-1][-2000 * 8:]
    i_ab = out[:, [COL["i_a"], COL["i_b"]]]
    applied = out[:, [COL["v_a"], COL["v_b"]]]
    va, vb = _alpha_beta(ds.startup, "v")
    ideal = np.repeat(np.column_stack([va, vb])[LAST], 8, axis=0)
    loss = 1.5 * np.mean(np.sum((ideal - applied) * i_ab, axis=1))
    s3 = math.sqrt(3) / 2
    i3 = np.column_stack([i_ab[:, 0], -0.5 * i_ab[:, 0] + s3 * i_ab[:, 1], -0.5 * i_ab[:, 0] - s3 * i_ab[:, 1]])
    mean_abs, mean_sq = np.abs(i3).mean(axis=0).sum(), (i3**2).mean(axis=0).sum()
    low = min(eff["V_T"], eff["V_D"]) * mean_abs + eff["r"] * mean_sq
    high = max(eff["V_T"], eff["V_D"]) * mean_abs + eff["r"] * mean_sq
    assert 0.97 * low < loss < 1.03 * high + 2.0  # + dead-time volt-seconds at the six edges


def test_hard_clipping_caps_the_currents(base):
    ds = _run(["current_sensor_saturation"], forms={"current_sensor_saturation": "clip"},
              sizes={"current_sensor_saturation": {"size": 2.0}})
    level = ds.truth["effects"][0]["level"]
    assert level == pytest.approx(2.0 * get_motor(MOTOR).rated_current_peak)
    for ch in ("i_r", "i_s"):
        assert np.max(np.abs(ds.startup[ch])) == pytest.approx(level)
        assert np.max(np.abs(base.startup[ch])) > 1.5 * level
        free = np.abs(base.startup[ch]) < level
        np.testing.assert_allclose(ds.startup[ch][free], base.startup[ch][free], rtol=0, atol=1e-12)


def test_speed_gain_scales_the_steady_speed(base):
    ds = _run(["speed_sensor_gain"], forms={"speed_sensor_gain": "gain"},
              sizes={"speed_sensor_gain": {"size": 0.04, "offset": 0.5}})
    np.testing.assert_allclose(ds.startup["speed"], 1.04 * base.startup["speed"] + 0.5, rtol=1e-12, atol=1e-9)


def test_offsets_show_as_dc_means(base):
    offs = {"current_offsets": [0.2, -0.1], "voltage_offsets": [3.0, -1.5, 0.8]}
    ds = _run(["sensor_offset"], forms={"sensor_offset": "both"}, sizes={"sensor_offset": offs})
    cycles = slice(-2000, None)  # 10 whole supply periods
    for ch, off in zip(("i_r", "i_s"), offs["current_offsets"], strict=True):
        assert ds.startup[ch][cycles].mean() == pytest.approx(off, abs=0.01)
    for ch, off in zip(("v_r", "v_s", "v_t"), offs["voltage_offsets"], strict=True):
        assert ds.startup[ch][cycles].mean() == pytest.approx(off, abs=0.1)


def test_channel_delay_lags_the_current_channel(base):
    ds = _run(["channel_delay"], forms={"channel_delay": "current_lag"}, sizes={"channel_delay": {"size": 1.5}})
    d = ds.truth["effects"][0]["achieved_size"]
    assert d == pytest.approx(1.5)
    t, i_true = base.startup["t"], base.startup["i_r"]
    lagged = np.interp(t - d / FS, t, i_true)
    k = slice(1000, None)
    assert np.max(np.abs(ds.startup["i_r"][k] - lagged[k])) < 0.02 * np.max(np.abs(i_true[k]))
    np.testing.assert_array_equal(ds.startup["v_r"], base.startup["v_r"])


def test_free_stop_is_cheap_and_follows_the_friction_law():
    ds = _run(scenario="dol", duration=0.5, stop=10.0)
    m = get_motor(MOTOR).machine
    t, w = ds.stop["t"], ds.stop["speed"]
    tau, c = m.J / m.fv, m.p * m.fc / m.J
    live = w > 5
    expected = (w[0] + tau * c) * np.exp(-t[live] / tau) - tau * c  # open contactor: no braking current
    assert np.max(np.abs(w[live] - expected)) < 0.05


# --- 4. seeds ------------------------------------------------------------------------------
def test_same_seed_same_files_other_seed_other_noise(tmp_path):
    noise = default_noise(get_motor(MOTOR))
    spec = _spec(duration=0.2, noise=noise, stop=1.0)
    a = write_dataset(make_dataset(spec), tmp_path / "a")
    b = write_dataset(make_dataset(spec), tmp_path / "b")
    for name in ("meta.yaml", "startup.csv", "stop.csv", "truth.yaml"):
        assert (a / name).read_bytes() == (b / name).read_bytes()
    other = make_dataset(_spec(duration=0.2, noise=noise, stop=1.0, seed=6))
    first = make_dataset(spec)
    assert not np.array_equal(other.startup["i_r"], first.startup["i_r"])
    noise = first.startup["i_r"] - base_clean(0.2)["i_r"]
    assert 0.5 * spec["noise"]["current_white"] < np.std(noise) < 3 * spec["noise"]["current_white"]


def base_clean(duration):
    return _run(duration=duration).startup


def test_blind_draw_is_reproducible_and_valid():
    from synthetic.independent import draw_blind_set

    a = draw_blind_set(np.random.default_rng(11))
    b = draw_blind_set(np.random.default_rng(11))
    assert a == b
    spec = draw_blind_set(np.random.default_rng(3), effects=["sensor_offset", "load_torque"], scenario="dol",
                          motor=MOTOR)
    spec["scenario"]["duration"] = 0.2
    spec["stop"] = None
    ds = make_dataset(spec)
    assert {e["name"] for e in ds.truth["effects"]} == {"sensor_offset", "load_torque"}
    assert ds.truth["source"] == "independent"


def test_a_scenario_given_a_duration_records_that_long_whatever_its_kind():
    """The blind runner's ``plant_duration`` sets a drawn scenario's length: a six-step start
    states it as whole cycles (it has no ``duration``; setting one made the plant raise), the grid
    and PWM starts as ``duration``; the six-step's own draw uses the same count."""
    from synthetic.independent.dataset import build_scenario, draw_scenario, scenario_with_duration
    from synthetic.independent.motors import get_motor

    mo = get_motor("paper_1kw")
    fs = 12000.0
    for kind in ("six_step", "dol", "pwm"):
        sc = scenario_with_duration(draw_scenario(kind, mo, 1.0, fs, None), 0.25, fs)
        made = build_scenario(sc)
        samples = made.samples() if kind == "six_step" else int(round(made.duration * fs))
        assert abs(samples / fs - 0.25) <= 6 * sc.get("Nc", 1) / fs, kind
    assert draw_scenario("six_step", mo, 0.25, fs, None) == scenario_with_duration(
        draw_scenario("six_step", mo, 1.0, fs, None), 0.25, fs)

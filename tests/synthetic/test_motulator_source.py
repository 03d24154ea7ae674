"""motulator as an independent data source: the referral, the data contract, determinism.

The checks that can fail: motulator's no-load steady state against the T-circuit phasor
solution of the referred parameters, and an inline RK4 of the project's 5-state model
(Lr = Ls) driven by the recorded voltages against motulator's recorded currents and speed.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest
import yaml
from scipy.optimize import brentq

from synthetic import motulator_source as ms

PAR = {"Rs": 4.96434, "Ls": 0.1075, "Le": 0.01098, "Rr": 1.55618, "J": 0.003, "fv": 0.00033, "fc": 0.04297}
SMALL = {"name": "small_2pole", "pole_pairs": 1, "voltage": 230.0, "frequency": 50.0, "parameters": PAR}
META_KEYS = {"kind", "pole_pairs", "sample_time", "input_hold", "dc_link_voltage", "supply_frequency", "inertia",
             "speed_unit", "description"}


@pytest.fixture(scope="module")
def motulator():
    return pytest.importorskip("motulator")


def read_csv(path):
    d = np.genfromtxt(path, delimiter=",", names=True)
    return {n: d[n] for n in d.dtype.names}


def alpha_beta(d):
    """Amplitude-invariant Clarke transform of the recorded phase quantities."""
    va = (2 / 3) * (d["v_r"] - 0.5 * (d["v_s"] + d["v_t"]))
    vb = (d["v_s"] - d["v_t"]) / np.sqrt(3)
    ia, ib = d["i_r"], (d["i_r"] + 2 * d["i_s"]) / np.sqrt(3)  # i_t = -(i_r + i_s)
    return va, vb, ia, ib


def rk4_project_model(par, p, t, va, vb, hold):
    """The project's model (Lr = Ls), classical RK4 with one step per sample."""
    Rs, Ls, Le, Rr, J, fv, fc = (par[k] for k in ("Rs", "Ls", "Le", "Rr", "J", "fv", "fc"))
    Lr, Lm = Ls, np.sqrt(Ls * (Ls - Le))
    Re = Rs + (Lm / Lr) ** 2 * Rr
    a11, a33, c1, c2 = Re / Le, Rr / Lr, 1 / Le, Lm / (Le * Lr)
    a13, a31 = a33 * c2, Rr * Lm / Lr

    def f(x, v):
        ia, ib, pa, pb, w = x
        T = 1.5 * p * Lm / Lr * (pa * ib - pb * ia)
        if w == 0.0 and abs(T) <= fc:
            dw = 0.0  # stiction
        else:
            dw = -w * fv / J + p / J * (T - fc * np.sign(w if w != 0.0 else T))
        return np.array([-a11 * ia + a13 * pa + c2 * w * pb + c1 * v[0], -a11 * ib + a13 * pb - c2 * w * pa + c1 * v[1],
                         a31 * ia - a33 * pa - w * pb, a31 * ib - a33 * pb + w * pa, dw])

    X, x, h = np.zeros((len(t), 5)), np.zeros(5), t[1] - t[0]
    for k in range(len(t) - 1):
        v0 = np.array([va[k], vb[k]])
        v1 = np.array([va[k + 1], vb[k + 1]]) if hold == "linear" else v0
        vm = 0.5 * (v0 + v1)
        k1 = f(x, v0)
        k2 = f(x + 0.5 * h * k1, vm)
        k3 = f(x + 0.5 * h * k2, vm)
        k4 = f(x + h * k3, v1)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        X[k + 1] = x
    X[:, 4] /= p  # mechanical speed
    return X


def phasor_no_load(par, p, U, f):
    """T-circuit steady state at the slip where air-gap torque meets friction: (speed, slip, |i| peak)."""
    Lm = np.sqrt(par["Ls"] * (par["Ls"] - par["Le"]))
    Ll = par["Ls"] - Lm  # Lr = Ls: equal leakages
    w, V = 2 * np.pi * f, np.sqrt(2 / 3) * U

    def circuit(s):
        Zr, Zm = par["Rr"] / s + 1j * w * Ll, 1j * w * Lm
        I = V / (par["Rs"] + 1j * w * Ll + Zm * Zr / (Zm + Zr))
        Ir = I * Zm / (Zm + Zr)
        return 1.5 * p * abs(Ir) ** 2 * par["Rr"] / s / w, abs(I)

    def excess(s):
        wm = w / p * (1 - s)
        return circuit(s)[0] - (par["fv"] * wm + par["fc"])

    s = brentq(excess, 1e-9, 0.5)
    return w / p * (1 - s), s, circuit(s)[1]


def test_missing_motulator_gives_install_hint(monkeypatch):
    for name in [n for n in sys.modules if n == "motulator" or n.startswith("motulator.")] + ["motulator"]:
        monkeypatch.setitem(sys.modules, name, None)
    monkeypatch.setattr(ms, "_CACHE", {})
    with pytest.raises(ImportError, match=r"motulator is not installed: pip install -e \.\[validation\]"):
        ms.load_motulator()


def test_referrals_agree():
    g = ms.gamma_from_project(PAR)
    back = ms.project_from_gamma(**{k: g[k] for k in ("R_s", "R_r", "L_ell", "L_s")})
    for k in ("Rs", "Ls", "Le", "Rr"):
        assert back[k] == pytest.approx(PAR[k], rel=1e-12)
    Lm = np.sqrt(PAR["Ls"] * (PAR["Ls"] - PAR["Le"]))
    t = ms.project_from_t_model(PAR["Rs"], PAR["Rr"], PAR["Ls"] - Lm, PAR["Ls"] - Lm, Lm)
    assert t["Le"] == pytest.approx(PAR["Le"], rel=1e-12) and t["Rr"] == pytest.approx(PAR["Rr"], rel=1e-12)
    # an unequal-leakage T model keeps the stator-side invariants: Ls, sigma*Ls, Lr/Rr
    t2 = ms.project_from_t_model(1.0, 0.8, 0.004, 0.006, 0.15)
    assert t2["Ls"] / t2["Rr"] == pytest.approx(0.156 / 0.8, rel=1e-12)
    assert t2["Le"] == pytest.approx(0.154 * (1 - 0.15**2 / (0.154 * 0.156)), rel=1e-12)


def test_inverse_gamma_referral_matches_motulators_conversion(motulator):
    from motulator.drive.utils import InductionMachineInvGammaPars, InductionMachinePars

    g = ms.gamma_from_project(PAR)
    inv = InductionMachineInvGammaPars.from_gamma_model_pars(InductionMachinePars(n_p=1, **g))
    p = ms.project_from_inverse_gamma(inv.R_s, inv.R_R, inv.L_sgm, inv.L_M)
    for k in ("Rs", "Ls", "Le", "Rr"):
        assert p[k] == pytest.approx(PAR[k], rel=1e-12)


def test_no_load_steady_state_matches_phasor_solution(motulator, tmp_path):
    ms.make_motulator_dataset(SMALL, "dol", None, None, 0, tmp_path, duration=0.8, sample_rate=4000, stop=False)
    d = read_csv(tmp_path / "startup.csv")
    _, _, ia, ib = alpha_beta(d)
    last = slice(-160, None)  # the last 40 ms, two supply periods
    speed, slip, amp = phasor_no_load(PAR, 1, 230.0, 50.0)
    w_sync = 2 * np.pi * 50.0
    assert np.mean(d["speed"][last]) == pytest.approx(speed, rel=0.01)
    assert 1 - np.mean(d["speed"][last]) / w_sync == pytest.approx(slip, rel=0.02)
    assert np.mean(np.hypot(ia, ib)[last]) == pytest.approx(amp, rel=0.01)


@pytest.mark.parametrize("scenario", ["dol", "six_step"])
def test_project_model_reproduces_motulator_start(motulator, tmp_path, scenario):
    ms.make_motulator_dataset(SMALL, scenario, None, None, 0, tmp_path, duration=0.3, sample_rate=10000, stop=False)
    meta = yaml.safe_load((tmp_path / "meta.yaml").read_text())
    d = read_csv(tmp_path / "startup.csv")
    va, vb, ia, ib = alpha_beta(d)
    X = rk4_project_model(PAR, 1, d["t"], va, vb, meta["input_hold"])
    peak = np.max(np.hypot(ia, ib))
    assert np.max(np.hypot(ia - X[:, 0], ib - X[:, 1])) < 0.01 * peak
    assert np.max(np.abs(d["speed"] - X[:, 4])) < 0.005 * np.max(np.abs(d["speed"]))


def test_same_seed_same_files(motulator, tmp_path):
    noise = {"current_std": 0.05, "current_colored_std": 0.02, "speed_std": 0.2, "speed_quantum": 0.5,
             "voltage_std": 0.5}
    for folder, seed in (("a", 7), ("b", 7), ("c", 8)):
        ms.make_motulator_dataset(SMALL, "six_step", None, noise, seed, tmp_path / folder, duration=0.05,
                                  sample_rate=5000, stop=False)
    for name in ("meta.yaml", "startup.csv", "truth.yaml"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    assert (tmp_path / "a" / "startup.csv").read_bytes() != (tmp_path / "c" / "startup.csv").read_bytes()


def test_folder_contract_and_short_circuit_stop(motulator, tmp_path):
    truth = ms.make_motulator_dataset(SMALL, "six_step", None, None, 0, tmp_path, duration=0.15, sample_rate=10000,
                                      stop=True, stop_mode="short", stop_sample_rate=1000, stop_max_duration=0.3)
    meta = yaml.safe_load((tmp_path / "meta.yaml").read_text())
    assert set(meta) <= META_KEYS and meta["kind"] == "startup" and meta["input_hold"] == "zoh"
    assert meta["pole_pairs"] == 1 and meta["sample_time"] == pytest.approx(1e-4)
    assert meta["dc_link_voltage"] == pytest.approx(0.5 * np.pi * np.sqrt(2 / 3) * 230.0)
    start = read_csv(tmp_path / "startup.csv")
    assert list(start) == ["t", "v_r", "v_s", "v_t", "i_r", "i_s", "speed"]
    assert set(np.round(np.abs(start["v_r"]) * 3 / meta["dc_link_voltage"], 9)) <= {1.0, 2.0}
    stop = read_csv(tmp_path / "stop.csv")
    assert list(stop) == ["t", "speed"] and stop["t"][0] == 0.0
    assert stop["speed"][0] == pytest.approx(start["speed"][-1], rel=1e-6)
    assert stop["speed"][-1] < stop["speed"][0]
    disk = yaml.safe_load((tmp_path / "truth.yaml").read_text())
    assert disk["source"] == "motulator" and disk == truth
    assert disk["parameters"] == pytest.approx(PAR)


def test_effects_and_refusals(motulator, tmp_path):
    effects = {"main_saturation": {"size": 0.3}, "two_mass": {"size": 0.4, "resonance_hz": 40.0},
               "load_torque": {"form": "step", "torque": 0.5, "time": 0.05}}
    truth = ms.make_motulator_dataset(SMALL, "dol", effects, None, 0, tmp_path, duration=0.1, sample_rate=5000,
                                      stop=False)
    assert [e["name"] for e in truth["effects"]] == list(effects)
    sat = truth["effects"][0]["form"]
    assert sat["L_unsaturated"] == pytest.approx(1.3 * PAR["Ls"])
    assert PAR["Ls"] == pytest.approx(sat["L_unsaturated"] / (1 + (sat["rated_flux"] / sat["knee_flux"]) ** 7))
    assert np.all(np.isfinite(read_csv(tmp_path / "startup.csv")["speed"]))
    with pytest.raises(ValueError, match="iron_loss.*not available from the motulator source"):
        ms.make_motulator_dataset(SMALL, "dol", {"iron_loss": {}}, None, 0, tmp_path, 0.01, 5000, False)
    with pytest.raises(ValueError, match="scenario"):
        ms.make_motulator_dataset(SMALL, "star_delta", None, None, 0, tmp_path, 0.01, 5000, False)


def test_the_speed_sensor_filter_comes_before_the_noise():
    """``noise["speed_filter"]``: an RC filter on the simulated speed (a ramp of ``a`` rad/s^2
    reads ``tau a`` low once settled), then the white noise of ``speed_std`` unchanged; none by
    default."""
    from synthetic.motulator_source import _speed_noise

    dt, acc, tau = 1e-4, 500.0, 3e-3
    ramp = acc * dt * np.arange(4000)
    clean = _speed_noise(np.random.default_rng(0), {}, ramp, dt)
    np.testing.assert_array_equal(clean, ramp)
    lagged = _speed_noise(np.random.default_rng(0), {"speed_filter": tau}, ramp, dt)
    assert lagged[-1] == pytest.approx(ramp[-1] - tau * acc, rel=1e-6)
    noisy = _speed_noise(np.random.default_rng(0), {"speed_filter": tau, "speed_std": 0.1}, ramp, dt)
    assert np.std(noisy - lagged) == pytest.approx(0.1, rel=0.05)

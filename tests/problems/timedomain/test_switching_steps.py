"""A sampled switch-on: the first contact found behind a two-pole stage, the volt-seconds of the
steps between samples estimated from the current's response and corrected, the switching window
masked; on an independent-plant record the model at the true parameters then fits the currents
at the noise level."""

from __future__ import annotations

import math
import warnings

import numpy as np
import yaml

from benchmark.problems.timedomain.data import load_startup_dataset
from benchmark.problems.timedomain.problem import TimeDomainProblem
from benchmark.problems.timedomain.switch_on import detect_switch_on, sampled_volt_seconds, switching_steps
from synthetic.independent import make_dataset, make_spec, write_dataset
from synthetic.independent.motors import get_motor

TS = 1e-4


def _rl_switch_on(events, n=120, L=0.01, R=1.0, w=2 * np.pi * 50, fine=400):
    """Samples of a rotating voltage switched on in steps (``events``: (time in samples,
    amplitude)) across an RL load, and its current, integrated exactly on a fine grid."""
    t = np.arange(n * fine + 1) * TS / fine
    amp = np.zeros_like(t)
    for at, a in events:
        amp[t >= at * TS] = a
    v = amp * np.exp(1j * w * t)
    a = math.exp(-R / L * TS / fine)
    i = np.zeros_like(v)
    for k in range(1, len(t)):  # exact for a voltage held over each fine step (mean of its ends)
        i[k] = a * i[k - 1] + (1 - a) / R * 0.5 * (v[k - 1] + v[k])
    return v[::fine][:n], i[::fine][:n]


def test_switching_step_fraction_and_inductance_from_the_current():
    V, I = _rl_switch_on([(20.3, 300.0), (27.8, 450.0)])
    got = switching_steps(V.real, V.imag, I.real, I.imag, 20, TS)
    assert 20 in got.steps and 27 in got.steps
    frac = dict(zip(got.steps, got.fractions, strict=True))
    assert abs(frac[20] - 0.7) < 0.03 and abs(frac[27] - 0.2) < 0.03, frac
    assert abs(got.inductance / 0.01 - 1) < 0.03
    # the masked window: from the sample before the first step to two samples after the last
    assert got.mask[20] and got.mask[got.steps[-1] + 2] and not got.mask[19] and not got.mask[got.steps[-1] + 3]
    # the interpolated volt-seconds over the window are now those of the continuous voltage
    t = np.arange(19, 40)
    Vc = got.v_a + 1j * got.v_b
    fine_v, _ = _rl_switch_on([(20.3, 300.0), (27.8, 450.0)], n=41, fine=400)
    exact = np.sum(0.5 * (fine_v[t] + fine_v[t + 1]))  # the samples' trapezoid...
    rot = np.exp(1j * 2 * np.pi * 50 * TS * np.array([21, 28]))
    exact += 300 * rot[0] * (0.7 - 0.5) + 150 * rot[1] * (0.2 - 0.5)  # + each step's (f - 1/2) dV
    assert abs(np.sum(0.5 * (Vc[t] + Vc[t + 1])) - exact) < 0.02 * 300
    # no step, nothing done
    V0, I0 = _rl_switch_on([(0.0, 300.0)])
    none = switching_steps(V0.real, V0.imag, I0.real, I0.imag, 0, TS)
    assert none.steps == () and not none.mask.any() and np.array_equal(none.v_a, V0.real)


def test_sampled_volt_seconds_of_a_sine():
    w = 2 * np.pi * 60
    ts = 1 / 6000
    t = np.arange(400) * ts
    v = np.cos(w * t)
    exact = (np.sin(w * t[1:]) - np.sin(w * t[:-1])) / (w * ts)
    chord = 0.5 * (v[:-1] + v[1:])
    fixed = sampled_volt_seconds(v, 1)
    restored = 0.5 * (fixed[:-1] + fixed[1:])
    inner = slice(1, -1)
    assert np.max(np.abs(chord - exact)[inner]) > 2e-4          # (w Ts)^2 / 12 lost by the chord
    assert np.max(np.abs(restored - exact)[inner]) < 3e-7       # fourth order left
    # the sum changes only by the end terms (the second differences telescope)
    ends = ((v[0] - v[1]) + (v[-1] - v[-2])) / 12
    assert abs(np.sum(fixed) - np.sum(v) + ends) < 1e-12


def test_first_contact_behind_a_two_pole_stage():
    n = 3000
    t = np.arange(n) * TS
    th = 2 * np.pi * 50 * t
    k2, k3 = 1000, 1012  # two poles close at k2 (a line-line voltage on R and S), the third at k3
    v = np.vstack([325 * np.cos(th - 2 * np.pi * q / 3) for q in range(3)])
    e_rs = v[0] - v[1]
    v[:, :k2] = 0.0
    v[0, k2:k3], v[1, k2:k3], v[2, k2:k3] = e_rs[k2:k3] / 2, -e_rs[k2:k3] / 2, 0.0
    assert detect_switch_on(v, TS) == k2


def test_independent_dol_record_fits_at_the_noise_level(tmp_path):
    mo = get_motor("simulink_7k5")
    sigma = 0.003 * mo.rated_current_peak
    spec = make_spec("simulink_7k5", "dol", [], seed=5, duration=0.6, noise={"current_white": sigma,
                                                                              "speed_white": 0.05})
    folder = write_dataset(make_dataset(spec), tmp_path / "rec")
    truth = yaml.safe_load((folder / "truth.yaml").read_text())["parameters"]
    x = np.array([truth[k] for k in ("Rs", "Ls", "Le", "Rr", "J", "fv", "fc")])

    def misfit(conditioning):
        meta = yaml.safe_load((folder / "meta.yaml").read_text())
        meta["conditioning"] = conditioning
        (folder / "meta.yaml").write_text(yaml.safe_dump(meta))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ds = load_startup_dataset(folder)
        p = TimeDomainProblem(ds, x * 0.5, x * 2)
        rms = {name: math.sqrt(float(np.mean(r**2))) for name, r, _ in p.fit_channels(x)}
        return ds, rms["i_alpha"] / sigma  # i_alpha = i_r: its noise is the phase noise

    raw_ds, raw = misfit(False)
    ds, fixed = misfit(True)
    text = "\n".join(ds.conditioning)
    assert "voltage steps between samples" in text and "current samples of the switching window masked" in text
    assert ds.startups[0].weight is not None and 3 <= int((~ds.startups[0].weight).sum()) <= 40
    assert raw > 1.5 and fixed < 1.1, (raw, fixed)

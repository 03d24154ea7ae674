"""The speed noise of a coarsely quantised tachometer
(:func:`benchmark.problems.timedomain.noise.startup_noise`).

Independent plant, an effect-free blind draw (``benchmark.blind source=plant seed=3``, set 1): a
7.5 kW 6-pole motor started direct-on-line from a 220 V / 60 Hz grid, its speed read in steps of
0.186 rad/s with 0.016 rad/s of white noise. At standstill and at steady state the reading sits
on one level, so the steady-state estimate sees next to nothing (it was floored at 1e-4 of the
speed, 0.013 rad/s); the run-up crosses every level and leaves the full quantisation error,
``q / sqrt(12)`` = 0.054 rad/s, in the residual. The diagnosis called this effect-free start
``unexplained`` at 1.21 times the noise. The grid must be found on the whole channel.
"""

from __future__ import annotations

import copy
import math

import numpy as np

import benchmark.problems.timedomain.noise as noise
from benchmark.problems.timedomain.conditioning import condition_dataset
from benchmark.problems.timedomain.data import load_startup_dataset
from synthetic.independent import draw_blind_set, make_dataset, write_dataset


def _blind_spec():
    """The draw of set 1 of the plant source with seed 3 (as benchmark.analysis.blind_sources)."""
    rng = np.random.default_rng(np.random.SeedSequence(3).spawn(24)[1])
    kind = str(rng.choice(["dol", "six_step", "pwm"], p=[0.4, 0.35, 0.25]))
    return draw_blind_set(rng, effects=[], scenario=kind)


def _record(spec, folder):
    return condition_dataset(load_startup_dataset(write_dataset(make_dataset(spec), folder))).startups[0]


def test_a_coarse_speed_step_sets_the_speed_noise_even_where_the_reading_stands_still(tmp_path):
    spec = _blind_spec()
    q = spec["noise"]["speed_quantum"]
    assert spec["motor"] == "fitzgerald_6pole" and abs(q - 0.186) < 1e-3 and spec["effects"] == []
    clean = copy.deepcopy(spec)
    clean["noise"].update({"speed_white": 0.0, "speed_quantum": 0.0})
    rec, ref = _record(spec, tmp_path / "noisy"), _record(clean, tmp_path / "clean")
    err = rec.speed - ref.speed
    period = int(round(1.0 / (60.0 * float(np.median(np.diff(rec.t))))))
    k_ss = noise.steady_start(rec.speed, len(rec.t), period)
    run_up = (rec.speed > 0.05 * rec.speed.max()) & (rec.speed < 0.95 * rec.speed.max())
    assert noise.quantum(rec.speed[k_ss:]) == 0.0  # the steady state alone shows no grid
    assert abs(noise.quantum(rec.speed) - q) < 1e-9
    assert abs(np.std(err[run_up]) - q / math.sqrt(12.0)) < 0.1 * q / math.sqrt(12.0)
    est = noise.startup_noise(rec.t, rec.v_alpha, rec.v_beta, rec.i_alpha, rec.i_beta, rec.speed, 60.0, True)
    assert noise.noise_from_smooth(rec.speed[k_ss:], 101).std < 0.2 * q / math.sqrt(12.0)
    assert 0.9 < est["speed"].std / float(np.std(err[run_up])) < 1.15, (est["speed"].std, np.std(err[run_up]))
    assert "floored" in est["speed"].method

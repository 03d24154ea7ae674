"""A tachometer's commutator ripple is noise to the model
(:func:`benchmark.problems.timedomain.noise.steady_speed_noise`).

The independent plant's tachometer adds a ripple of ``speed_ripple`` rad/s at ``ripple_order``
periods per revolution. On a 2-pole motor near synchronous speed that is within a fraction of
a hertz of the ``ripple_order``-th supply harmonic, and the speed's harmonic fit, run at every
supply harmonic, took it out of the noise: 0.53-0.54 times the noise really added on the 1 kW
motor's direct-on-line starts at orders 7, 11 and 13 (seeds 0-2), so every model's speed
residual came out at about 3.4 times its chi^2 share. A three-phase supply makes the torque
pulsate only at twice its frequency (unbalance) and at multiples of six (its 5th and 7th, 11th
and 13th, ... harmonics); the fit now runs at those orders only, and the ripple at 11 or 13 per
revolution stays in the noise.

Of those, only the orders the record's own voltage makes: a grid holds a 5th and a 7th and no
11th or 13th, so its motor's torque has no 12th line. A 4-pole motor's tachometer with 24
segments (the independent plant's 7.5 kW calibration start: 0.0996 rad/s at ~599 Hz) sat on the
12th, was taken out (the speed's noise 0.010 rad/s against 0.072 really added), and an
effect-free start was called ``unexplained``; now the voltage is read first
(:func:`benchmark.problems.timedomain.noise.supplied_torque_orders`) and a 12th per revolution
of a grid- or PWM-fed 2-pole start stays in (0.54 and 0.57 before, 1.01 and 0.99 now). Where the
supply does make that line (a six-step inverter's 11th and 13th) the ripple is still taken out
(0.54): the speed alone cannot tell it from the supply's torque ripple.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmark.problems.timedomain.conditioning import condition_dataset
from benchmark.problems.timedomain.data import load_startup_dataset
from benchmark.problems.timedomain.noise import record_noise, supplied_torque_orders
from synthetic.independent import make_dataset, make_spec, write_dataset

SPEED_WHITE = 0.04  # rad/s
RIPPLE = 0.09  # rad/s amplitude


def _speed_noise_ratio(kind: str, order: int, folder) -> tuple[float, str]:
    noise = dict(current_white=0.05, current_colored=0.0, current_pole=0.9, current_quantum=0.0,
                 voltage_white=0.5, voltage_quantum=0.0, speed_white=SPEED_WHITE, speed_quantum=0.0,
                 speed_ripple=RIPPLE, ripple_order=order)
    spec = make_spec("paper_1kw", kind, [], seed=0, duration=1.2, noise=noise)
    ds = condition_dataset(load_startup_dataset(write_dataset(make_dataset(spec), folder)))
    est, _ = record_noise(ds.startups[0], ds.supply_frequency)
    return est["speed"].std / math.hypot(SPEED_WHITE, RIPPLE / math.sqrt(2.0)), est["speed"].method


@pytest.mark.parametrize("kind, order", [("dol", 11), ("six_step", 13), ("dol", 12), ("pwm", 12)])
def test_a_commutator_ripple_off_the_supplys_torque_lines_stays_in_the_speed_noise(kind, order, tmp_path):
    ratio, method = _speed_noise_ratio(kind, order, tmp_path)
    # the speed noise against the noise really added: before 0.54 (dol 11, six_step 13, dol 12)
    # and 0.57 (pwm 12), now 0.99-1.01
    assert 0.93 < ratio < 1.07, (ratio, method)


def test_a_ripple_on_a_line_the_supply_makes_is_still_taken_for_the_supplys_torque_ripple(tmp_path):
    # a six-step voltage holds the 11th and 13th: the 12th torque line is fitted, and a
    # tachometer's 12 per revolution of a 2-pole motor with it (the limit this estimate has)
    ratio, method = _speed_noise_ratio("six_step", 12, tmp_path)
    assert 0.45 < ratio < 0.62, (ratio, method)
    assert "19 harmonics" in method, method


def test_the_torque_lines_a_supply_makes_are_read_from_its_voltage():
    fs, f0 = 10_000.0, 50.0
    t = np.arange(4000) / fs
    w = 2 * np.pi * f0 * t

    def vector(*lines):  # (signed order, amplitude share of the fundamental)
        return 325.0 * sum(a * np.exp(1j * h * w) for h, a in ((1, 1.0), *lines))

    grid = vector((-5, 0.02), (7, 0.01))
    assert supplied_torque_orders(grid.real, grid.imag, fs, f0).tolist() == [6]
    unbalanced = vector((-1, 0.005), (-5, 0.02))
    assert supplied_torque_orders(unbalanced.real, unbalanced.imag, fs, f0).tolist() == [2, 6]
    six_step = vector(*[(h, 1.0 / abs(h)) for k in range(1, 16) for h in (-(6 * k - 1), 6 * k + 1)])
    assert supplied_torque_orders(six_step.real, six_step.imag, fs, f0).tolist() == list(range(6, 96, 6))
    # a 13th of 0.05 % is below 1e-3 of the fundamental: no 12th line
    weak = vector((-5, 0.02), (13, 0.0005))
    assert supplied_torque_orders(weak.real, weak.imag, fs, f0).tolist() == [6]

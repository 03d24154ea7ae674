"""The double-cage augmentation reaches the independent plant's deep-bar rotors.

The independent plant (``synthetic/independent``) builds a deep bar as a ladder of 3-6 bar
slices linked by the slot leakage, drawn at a resistance ratio ``R(50 Hz)/R(0)`` of 1.2-1.6. An
inverter-fed start drives the rotor at the supply's slip frequency and at the harmonics' (the
5th and 7th at 250-350 Hz, the 11th and 13th at 550-650 Hz), so the rotor impedance matters over
that whole range. The test fits the augmentation's rotor (its :meth:`augment` rows: cage 1, loop
2, loop 3; plus a free series leakage and low-slip resistance, which the base model's ``L_sigma``
and ``R_R`` carry) to the plant's rotor impedance at the corners of its draw range, on two of
the plant's motors.

Measured (relative RMS over 0-50 Hz and the harmonics): three loops at most 0.074 % (six slices,
ratio 1.6, 2.2 kW), exact for three slices; two loops (loop 3 held absent, the augmentation as it
was) 0.25-2.1 %, more at the harmonics: several times a start's current noise in the harmonic currents,
which is where the diagnosis of the plant's inverter-fed deep-bar sets left 1.7-2.4 times the
noise and hid the second effect of a pair (blind seed 57, sets 10 and 11).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import least_squares

from benchmark.core.effects import load_effects
from benchmark.problems.timedomain.extended import IDX, base_row
from synthetic.independent.motors import get_motor
from synthetic.independent.rotor import design
from tests.problems.timedomain.test_effects import PAPER_MOTOR, _ctx

CTX = _ctx()
EFFECT = load_effects("timedomain")["double_cage"]
W_E = 2 * np.pi * 50.0
#: rotor angular frequencies (rad/s): the slip range of a start, then the six-step harmonics
W = np.concatenate([np.linspace(0.5, W_E, 30), 2 * np.pi * np.array([250.0, 300.0, 350.0, 550.0, 600.0, 650.0])])


def augmented_impedance(x: np.ndarray, w: np.ndarray = W) -> np.ndarray:
    """Rotor impedance (ohm) of the augmentation with extras ``x[:4]``, low-slip resistance
    ``x[4]`` (ohm) and series leakage ``x[5]`` (H)."""
    eff = EFFECT
    row = base_row(PAPER_MOTOR)
    row[IDX["R_r1"]] = x[4]
    row[IDX["L_sigma"]] = 1.0  # large: any loop leakage fits under it
    row = eff.augment(row[None], x[None, :4], CTX)[0]
    y = 1.0 / row[IDX["R_r1"]] + 1.0 / (row[IDX["R_r2"]] + 1j * w * row[IDX["L_sigma2"]])
    if row[IDX["R_r3"]] > 0:
        y = y + 1.0 / (row[IDX["R_r3"]] + 1j * w * row[IDX["L_sigma3"]])
    return 1.0 / y + 1j * w * x[5]


def rms_fit(motor: str, ratio: float, slices: int, loops: int) -> float:
    """Relative RMS error of the best augmented rotor (``loops`` 2: loop 3 held absent)."""
    m = get_motor(motor).machine
    cage, _ = design("deep_bar", m.Rr, m.Llr, W_E, ratio, n=slices, max_growth=2.0)
    target = cage.impedance(W)
    R0, L0 = cage.low_slip()
    eff = EFFECT
    lo, hi = eff.extra_bounds(CTX)
    lo = np.concatenate([lo, [0.3 * R0, 0.0]])
    hi = np.concatenate([hi, [3.0 * R0, 2.0 * L0]])
    if loops == 2:
        hi[2] = 0.0
        lo[2] = 0.0

    def miss(p):
        x = np.concatenate([p[:2], [lo[2] if loops == 2 else p[2]], p[3:]])
        r = augmented_impedance(x) / target - 1.0
        return np.concatenate([r.real, r.imag])

    free = np.ones(len(lo), bool)
    free[2] = loops == 3
    lo_f, hi_f = lo[free], hi[free]

    def miss_free(pf):
        p = lo.copy()
        p[free] = pf
        return miss(p)

    starts = []
    for s in eff.extra_starts(CTX):
        x0 = np.concatenate([s, [R0, 0.3 * L0]])
        starts.append(np.clip(x0[free], lo_f + 1e-12 * (hi_f - lo_f), hi_f))
    best = min((least_squares(miss_free, s, bounds=(lo_f, hi_f), x_scale="jac") for s in starts),
               key=lambda r: r.cost)
    return float(np.sqrt(2.0 * best.cost / len(W)))


CORNERS = [(motor, ratio, slices) for motor in ("paper_1kw", "motulator_2k2") for ratio in (1.2, 1.6)
           for slices in (3, 6)]


@pytest.mark.parametrize("motor,ratio,slices", CORNERS)
def test_three_loops_reach_the_plant_deep_bar(motor, ratio, slices):
    assert rms_fit(motor, ratio, slices, loops=3) < 2e-3


def test_two_loops_do_not():
    """Why loop 3: held absent, the worst corner misses by more than 1 %."""
    assert max(rms_fit(m, r, s, loops=2) for m, r, s in CORNERS if s == 6 and r == 1.6) > 1e-2

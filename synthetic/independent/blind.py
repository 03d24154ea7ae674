"""Random blind data-set specs: motor spread, scenario, effects (sizes and forms), noise.

:func:`draw_blind_set` returns a spec for :func:`synthetic.independent.dataset.make_dataset`.
What is drawn (all from the caller's generator, in a fixed order):

* motor: a preset, its T-circuit resistances, inductances, inertia and viscous friction each
  scaled by a log-normal factor (10 % spread), the leakage split ``Llr/Lls`` in 0.7-1.5, and
  ``fc`` 0.3-1.5 % of rated torque (or 0 with probability 0.3, unless ``coulomb_friction``
  is an effect of the set, which then sets it);
* scenario: ``dol`` (grid imperfections drawn), ``six_step`` or ``pwm`` (ramp drawn), record
  0.8-1.5 s (the motor's default sample rate), a free stop of 2-10 s with probability 0.5;
* effects: the given names, or ``n_effects`` names drawn from the catalogue (``inverter_drop``
  only for inverter scenarios); sizes and forms from each effect's draw, the forms from the
  form set ``forms`` (``development`` by default, ``heldout`` or ``all``:
  :mod:`~synthetic.independent.forms`);
* noise: white current noise 0.2-1 % of rated current amplitude, AR(1) coloured 0-0.6 %
  (pole 0.9-0.995), a 12-16-bit current ADC over 6-10 x rated (probability 0.5), grid
  voltage noise 0.1-1 V and a 12-16-bit voltage ADC over 1.5 x the rated phase amplitude
  (probability 0.5; measured grid voltages only), speed noise 0.01-0.1 rad/s, speed quantum 0.01-0.2 rad/s
  (probability 0.7), commutator ripple up to 0.1 rad/s (probability 0.3);
* sensors: no speed sensor with probability 0.1, a torque sensor with probability 0.2;
  nameplate in meta.yaml with probability 0.7, the cold stator DC resistance with 0.5.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from synthetic.independent.dataset import draw_scenario
from synthetic.independent.effects import EFFECTS, get_effect
from synthetic.independent.machine import TMachine
from synthetic.independent.motors import PRESETS, get_motor


def _spread_machine(rng: np.random.Generator, m: TMachine, fc: float) -> dict:
    f = {k: float(np.exp(rng.normal(0.0, 0.1))) for k in ("Rs", "Rr", "Lm", "Lls", "J", "fv")}
    split = float(rng.uniform(0.7, 1.5))
    Lls = m.Lls * f["Lls"]
    return {"Rs": m.Rs * f["Rs"], "Rr": m.Rr * f["Rr"], "Lm": m.Lm * f["Lm"], "Lls": Lls,
            "Llr": Lls * split * m.Llr / m.Lls, "J": m.J * f["J"], "fv": m.fv * f["fv"], "fc": fc}


def _noise(rng: np.random.Generator, In: float, V: float) -> dict:
    bits = int(rng.integers(12, 17))
    rng_adc = float(rng.uniform(6, 10)) * In
    v_bits = int(rng.integers(12, 17))
    return {
        "current_white": float(rng.uniform(0.002, 0.01) * In),
        "current_colored": float(rng.uniform(0.0, 0.006) * In),
        "current_pole": float(rng.uniform(0.9, 0.995)),
        "current_quantum": 2 * rng_adc / 2**bits if rng.random() < 0.5 else 0.0,
        "voltage_white": float(rng.uniform(0.1, 1.0)),
        "voltage_quantum": 2 * 1.5 * V / 2**v_bits if rng.random() < 0.5 else 0.0,
        "speed_white": float(rng.uniform(0.01, 0.1)),
        "speed_quantum": float(rng.uniform(0.01, 0.2)) if rng.random() < 0.7 else 0.0,
        "speed_ripple": float(rng.uniform(0.0, 0.1)) if rng.random() < 0.3 else 0.0,
        "ripple_order": int(rng.integers(8, 25)),
    }


def draw_blind_set(rng: np.random.Generator, effects=None, n_effects=(0, 3), motor: str | None = None,
                   scenario: str | None = None, forms: str = "development") -> dict:
    """A random data-set spec (see module docstring).

    Parameters
    ----------
    rng : the generator every choice comes from.
    effects : effect names to inject (None = draw ``n_effects`` of them).
    n_effects : a count, or an inclusive ``(low, high)`` range of counts.
    motor, scenario : fix the preset or the scenario kind instead of drawing them.
    forms : the form set the effects' forms are drawn from.
    """
    name = motor or str(rng.choice(sorted(PRESETS)))
    mo = get_motor(name)
    kind = scenario or str(rng.choice(["dol", "six_step", "pwm"], p=[0.4, 0.35, 0.25]))
    if effects is None:
        lo, hi = (n_effects, n_effects) if np.isscalar(n_effects) else n_effects
        n = int(rng.integers(lo, hi + 1))
        pool = [e for e in EFFECTS if not (EFFECTS[e].inverter_only and kind == "dol")]
        effects = [str(e) for e in rng.choice(pool, size=min(n, len(pool)), replace=False)]
    else:
        effects = list(effects)
        bad = [e for e in effects if get_effect(e).inverter_only and kind == "dol"]
        if bad:
            raise ValueError(f"{bad} need an inverter-fed scenario, not dol")
    fc = 0.0 if rng.random() < 0.3 else float(rng.uniform(0.003, 0.015) * mo.rated_torque)
    machine = _spread_machine(rng, mo.machine, fc)
    spread = mo.with_machine(replace(mo.machine, **machine))
    duration = float(rng.uniform(0.8, 1.5))
    stop = {"duration": float(rng.uniform(2.0, 10.0)), "sample_time": 1e-3} if rng.random() < 0.5 else None
    return {
        "motor": name, "machine": machine,
        "scenario": draw_scenario(kind, spread, duration, mo.sample_rate, rng),
        "sample_rate": float(mo.sample_rate), "oversampling": 10,
        "effects": [get_effect(e).draw(rng, spread, forms=forms, scenario=kind) for e in effects],
        "noise": _noise(rng, spread.rated_current_peak, spread.phase_peak),
        "sensors": {"has_speed": bool(rng.random() >= 0.1), "has_torque": bool(rng.random() < 0.2)},
        "stop": stop,
        "meta": {"nameplate": bool(rng.random() < 0.7), "dc_resistance": bool(rng.random() < 0.5)},
        "seed": int(rng.integers(0, 2**31 - 1)),
    }

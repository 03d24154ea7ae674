"""Physical priors of the effects (docs/effects.md): a winding's heating bounded by what the
record's currents can do to it, and the rated current that bound is measured against."""

from __future__ import annotations

import numpy as np
import pytest

from benchmark.core.effects import EffectContext, load_effects
from benchmark.problems.timedomain.diagnosis.scales import rated_current

HEAT = load_effects("timedomain", ["temperature_drift"])["temperature_drift"]


def _ctx(**kw):
    base = dict(w_e=314.16, V1=326.6, I_peak=150.0, w_sync=157.08, dc_link_voltage=0.0, E_cu=5000.0, L_M=0.12,
                L_sigma=0.006, pole_pairs=2)
    return EffectContext(**{**base, **kw})


def test_a_winding_cannot_heat_without_the_energy_to_do_it():
    """0.75 K/s at rated current (copper at 150 degC, 10 A/mm^2): a 7.5 kW motor's direct start
    (seven times its 14.5 A for 0.15 s, then 0.65 s at a third of it) may heat its stator by 5.5 K
    at most; a second at no load by 0.09 K."""
    assert HEAT.RATED_HEATING_RATE == pytest.approx(2.6e-8 * 1e14 / 3.45e6)
    start = (7 * 14.5) ** 2 * 0.15 + (14.5 / 3) ** 2 * 0.65
    assert HEAT.largest_rise(_ctx(I_rated=14.5, I2t=start)) == pytest.approx(0.7536 * start / 14.5**2, rel=1e-3)
    assert 5.0 < HEAT.largest_rise(_ctx(I_rated=14.5, I2t=start)) < 6.0
    assert HEAT.largest_rise(_ctx(I_rated=14.5, I2t=(0.35 * 14.5) ** 2)) < 0.1
    lo, hi = HEAT.extra_bounds(_ctx(I_rated=14.5, I2t=start))
    assert lo[0] == 0.0 and hi[0] == pytest.approx(HEAT.largest_rise(_ctx(I_rated=14.5, I2t=start)))
    s = HEAT.extra_starts(_ctx(I_rated=14.5, I2t=start))[0]
    assert lo[0] <= s[0] <= hi[0]
    assert HEAT.extra_bounds(_ctx())[1][0] == HEAT.UNBOUNDED_RISE  # no rated current known: the old box


def test_the_rated_current_is_the_nameplates_or_a_lower_bound_from_the_rated_power():
    ctx = _ctx()
    assert rated_current({"current": 15.2, "rated_power": 7500.0}, ctx, 50.0) == 15.2
    v_phase = 326.6 / np.sqrt(2.0)
    assert rated_current({"rated_power": 7500.0}, ctx, 50.0) == pytest.approx(7500.0 / (3 * v_phase * 0.85))
    assert rated_current(None, ctx, 50.0) == pytest.approx(50.0 * 157.08 / (3 * v_phase * 0.85))
    # the simulink 7.5 kW motor's 14.5 A: the bound from its rated power is below it
    assert rated_current({"rated_power": 7500.0}, ctx, 50.0) < 14.5
    assert rated_current(None, _ctx(V1=0.0), 0.0) == 0.0

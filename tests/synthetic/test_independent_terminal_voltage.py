"""The independent plant records the motor-terminal voltage a voltmeter reads: at the step where
a contactor pole closes, a pole whose large 'open' resistance carries no current yet would show
the grid's EMF on the floating terminal for one internal step; the recorded value is the one just
after the change."""

from __future__ import annotations

import numpy as np

from synthetic.independent.dataset import terminal_voltage
from synthetic.independent.integrate import COL, OUT_COLS
from synthetic.independent.supply import MODE_GRID, MODE_OPEN, Grid, _empty


def test_change_step_reads_the_value_just_after_the_change():
    n, h = 40, 1e-5
    drv = _empty(n, h, MODE_GRID)
    drv.mode[:10] = MODE_OPEN
    drv.closed[10:, :2] = 1.0
    drv.closed[25:, 2] = 1.0
    out = np.zeros((n + 1, len(OUT_COLS)))
    ramp = 100.0 + 2.0 * np.arange(n + 1)
    out[:, COL["v_a"]] = ramp
    out[:, COL["v_b"]] = -ramp
    out[10, COL["v_a"]] = 400.0  # the floating terminal at the grid's EMF for one step
    out[25, COL["v_b"]] = -400.0
    v = terminal_voltage(out, drv, 0.0, h)
    np.testing.assert_allclose(v[:, 0], ramp[:-1])
    np.testing.assert_allclose(v[:, 1], -ramp[:-1])


def test_plant_dol_record_has_no_open_pole_spike():
    from synthetic.independent import make_dataset, make_spec

    # the poles closing on sample instants (the plant sampled the open pole's transient there:
    # 323 V on a 326 V grid at the second pole's closing, 105 V one sample later)
    spec = make_spec("simulink_7k5", "dol", [], seed=1, duration=0.1, noise={})
    ts = 1.0 / spec["sample_rate"]
    sc = spec["scenario"]
    sc["pre_trigger"] = 100 * ts
    sc["stagger"] = [0.0, 3 * ts, 9 * ts]
    ds = make_dataset(spec)
    rec = ds.startup
    v = np.hypot(*[(2 / 3) * (rec["v_r"] - 0.5 * (rec["v_s"] + rec["v_t"])), (rec["v_s"] - rec["v_t"]) / np.sqrt(3)])
    level = Grid(V=ds.meta["nameplate"]["voltage"]).V * np.sqrt(2 / 3)
    k2, k3 = 103, 109  # the second pole closes (two phases on a line-line voltage), then the third
    # the closing samples are continuous with the samples after them, not at the grid's EMF
    assert abs(v[k2] - v[k2 + 1]) < 0.2 * level, (v[k2 - 1:k2 + 3], level)
    assert abs(v[k3] - v[k3 + 1]) < 0.02 * level, (v[k3 - 1:k3 + 3], level)

"""The channel offsets of a bench record as an effect, ``sensor_offset``.

DC offsets in the recorded voltage (V) and current (A) channels. A voltage offset drives a
DC current through the stator (the motor sees ``v - offset``: a kernel term); a current
offset is added to the record (a measurement). Size: the voltage offset's magnitude,
0.5-5 V; forms: ``current_offset`` magnitude, 0.05-0.3 A, ``parts`` (``both``, ``voltage``,
``current``), the offset vectors' directions ``angle_v``, ``angle_i`` (rad, alpha-beta).
Extras ``dv_alpha``, ``dv_beta`` (fractions of the fundamental voltage amplitude),
``di_alpha``, ``di_beta`` (fractions of the start-up current peak).

The record measures its offsets itself on a grid supply's steady tail
(:func:`benchmark.problems.timedomain.conditioning.offsets_left`): a fit the measurement excludes is
not named (:meth:`SensorOffset.contradicted`).
"""

from __future__ import annotations

import math

import numpy as np

from benchmark.core.effects import Effect
from benchmark.problems.timedomain.conditioning import OFFSET_COMPONENTS, OFFSET_STANDARD_ERRORS
from benchmark.problems.timedomain.extended import IDX


class SensorOffset(Effect):
    name = "sensor_offset"
    size_name = "voltage_offset"
    size_unit = "V"
    realistic = (0.5, 5.0)
    extra_names = ("dv_alpha", "dv_beta", "di_alpha", "di_beta")
    extra_units = ("p.u. of fundamental voltage amplitude", "p.u. of fundamental voltage amplitude",
                   "p.u. of recorded current peak", "p.u. of recorded current peak")
    physics = "DC offsets in the voltage (a few V) and current (tenths of A) channels"
    shows_in = "a false DC current; Rs biased up; a DC term in the residual"
    measure_stage = 2
    FORM_DRAWS = {"parts": {"choice": ["both", "voltage", "current"]}, "current_offset": [0.05, 0.3],
                  "angle_v": [0.0, 6.283185307179586], "angle_i": [0.0, 6.283185307179586]}

    def _offsets(self, size, form):
        form = {**self.form, **(form or {})}
        parts = str(form.get("parts", "both"))
        dv = float(size) if parts in ("both", "voltage") else 0.0
        di = float(form.get("current_offset", 0.1)) if parts in ("both", "current") else 0.0
        av, ai = float(form.get("angle_v", 0.5)), float(form.get("angle_i", 2.0))
        return dv * math.cos(av), dv * math.sin(av), di * math.cos(ai), di * math.sin(ai)

    def plant(self, row, size, ctx, form=None):
        return row.copy()  # the motor sees the true voltage; the record carries the offset

    def plant_voltages(self, v_a, v_b, size, ctx, form=None):
        dva, dvb, _, _ = self._offsets(size, form)
        return v_a + dva, v_b + dvb

    def plant_extras(self, size, ctx, form=None):
        dva, dvb, dia, dib = self._offsets(size, form)
        return np.array([dva / ctx.V1, dvb / ctx.V1, dia / ctx.I_peak, dib / ctx.I_peak])

    def extra_bounds(self, ctx):
        return np.array([-0.05, -0.05, -0.03, -0.03]), np.array([0.05, 0.05, 0.03, 0.03])

    def extra_starts(self, ctx):
        return [np.zeros(4)]

    def augment(self, rows, extras, ctx):
        rows = rows.copy()
        rows[:, IDX["v_off_a"]] = extras[:, 0] * ctx.V1
        rows[:, IDX["v_off_b"]] = extras[:, 1] * ctx.V1
        return rows

    def measure(self, sim, extras, ctx):
        extras = np.atleast_2d(extras)
        out = sim.copy()
        out[:, 0] = sim[:, 0] + extras[:, 2:3] * ctx.I_peak
        out[:, 1] = sim[:, 1] + extras[:, 3:4] * ctx.I_peak
        return out

    def measured_directly(self, ctx):
        """On a grid supply only (voltages measured, no DC link): a grid's voltage has no DC
        part, so the steady tail's means are the sensors' offsets. An inverter's applied voltage
        may carry one (a dead-time asymmetry) and drive a true DC current, which the model, fed
        that voltage, shares with the record; its tail's current means are no sensor's alone."""
        facts = ctx.facts
        grid = not facts.get("dc_link_voltage") and facts.get("input_hold") != "zoh"
        return grid and bool(facts.get("offsets_left"))

    def contradicted(self, extras, standard_errors, ctx):
        """The conditioning measured each channel's offset on the steady tail (whole supply
        periods, where neither the supply nor the machine's currents have a DC part) and left it
        in the record (``facts["offsets_left"]``, :func:`~benchmark.problems.timedomain.
        conditioning.offsets_left`). Where the tail finds no offset left on any channel (each
        within the conditioning's ``OFFSET_STANDARD_ERRORS`` of its standard error), a fitted
        offset more than that many combined standard errors from it is no offset (independent
        plant, calibration seed 501 set 15: 0.23 +- 0.05 A fitted beside a skew, taking what the
        skew's form left of a voltage lag, where the tail measured 0.001 +- 0.006 A). Where the
        tail finds one, the fit is not checked: a probe's offset may drift over the record, and
        the constant fitted to it is a compromise the tail's end need not agree with (held-out
        plant 414 set 22, a thermal drift: -0.13 A fitted, -0.10 A at the tail)."""
        scale = np.array([ctx.V1, ctx.V1, ctx.I_peak, ctx.I_peak])
        fitted, se = np.ravel(extras) * scale, np.ravel(standard_errors) * scale
        left = ctx.facts["offsets_left"]
        if any(abs(value) > OFFSET_STANDARD_ERRORS * value_se for value, value_se in left.values()):
            return None  # the tail finds an offset: a constant fitted to a drifting one lies elsewhere
        z = {k: abs(fitted[k] - left[name][0]) / math.hypot(se[k], left[name][1])
             for k, name in enumerate(OFFSET_COMPONENTS) if name in left}
        k = max(z, key=lambda k: z[k] if np.isfinite(z[k]) else -1.0, default=None)
        if k is None or not z[k] > OFFSET_STANDARD_ERRORS:
            return None
        name, unit = OFFSET_COMPONENTS[k], "V" if k < 2 else "A"
        return (f"its {name} offset {fitted[k]:.3g} +- {se[k]:.2g} {unit} is {z[k]:.1f} standard errors from "
                f"the {left[name][0]:.3g} +- {left[name][1]:.2g} {unit} the record's steady tail measures")

    def describe_fit(self, extras, ctx, base=None):
        x = np.ravel(extras)
        return {"dv_alpha_V": float(x[0] * ctx.V1), "dv_beta_V": float(x[1] * ctx.V1),
                "di_alpha_A": float(x[2] * ctx.I_peak), "di_beta_A": float(x[3] * ctx.I_peak)}

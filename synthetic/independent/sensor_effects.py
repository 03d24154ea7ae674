"""The sensor effects of the catalogue: probes, tachometer, offsets, channel timing.

Draw ranges (``I_n`` rated current amplitude, ``M`` internal steps per sample); held-out forms
marked (h), equations in :mod:`~synthetic.independent.sensors`,
:mod:`~synthetic.independent.probes` and ``docs/effect_forms.md``:

* ``current_sensor_saturation`` (``tanh``, ``knee``, ``clip``; (h) ``hall_core``: core
  exponent 5-12, coercive (magnetic-offset) current 0.3-1 % of ``I_n``): size = level /
  ``I_n``, 1.5-3. (h) ``current_transformer`` (``dol`` and ``six_step`` only): size = the
  amplitude of a rated-frequency sinusoid that reaches the knee, 2-4 ``I_n``; excitation
  exponent 8-16, secondary time constant 0.5-3 s, remanence up to 60 % of the knee flux per
  core, either sign.
* ``speed_sensor_gain`` (``gain``, ``gain_ripple``; ``tacho_filter``: first-order RC filter of
  1-5 ms on the tachometer, held out until the diagnosis was developed on it; (h)
  ``encoder_window``: an incremental encoder's speed, its count over a gate time of 1-5 ms):
  size = gain error, +-(1-5) % (fraction); offset up to
  +-0.5 % of synchronous speed; ripple at the rotation frequency 0.2-1 % of the speed
  (``gain_ripple``).
* ``sensor_offset`` (``both``, ``current``, ``voltage``): current offsets 0.05-0.3 A, voltage
  offsets 0.5-5 V, random signs; size = the largest current offset, A (the largest voltage
  offset, V, for ``voltage``). (h) ``thermal_drift``: the same offsets plus a drift of
  0.05-0.2 A (either sign, per probe) as each probe warms with its own current, thermal time
  constant 0.3-3 s; size = the largest current offset at the end of the record.
* ``channel_delay`` (``current_lag``, ``voltage_lag``): size = skew 0.1-2 samples, realised
  to a multiple of ``1/M`` (``achieved_size``). (h) ``anti_alias``: a second-order Bessel
  filter on the current channels, size = its group delay at DC, 0.5-2 samples (cut-off
  below the Nyquist frequency); ``mux_skew`` (retired from the held-out forms: a blind set
  states its card's sequence, and the diagnosis's channel skew follows it): a multiplexed card
  sampling ``i_r, i_s, v_r, v_s, v_t`` one after the other in a drawn order, size = the time
  between two channels, 0.1-0.3 samples (realised to a multiple of ``1/M``); inverter
  voltages are computed from the gates and have no slot delay.
"""

from __future__ import annotations

import math

import numpy as np

from synthetic.independent.effect_base import Effect, signed

MUX_CHANNELS = ("i_r", "i_s", "v_r", "v_s", "v_t")


class CurrentSensorSaturation(Effect):
    name, unit = "current_sensor_saturation", "x rated current amplitude"

    def _draw(self, rng, motor, form):
        if form == "hall_core":
            return {"size": float(rng.uniform(1.5, 3.0)), "exponent": float(rng.uniform(5.0, 12.0)),
                    "coercive": float(rng.uniform(0.003, 0.01))}
        if form == "current_transformer":
            return {"size": float(rng.uniform(2.0, 4.0)), "exponent": float(rng.uniform(8.0, 16.0)),
                    "secondary_time_constant": float(rng.uniform(0.5, 3.0)),
                    "remanence": [float(x) for x in rng.uniform(-0.6, 0.6, 2)]}
        return {"size": float(rng.uniform(1.5, 3.0))}

    def _apply(self, build, spec):
        In = build.motor.rated_current_peak
        level = spec["size"] * In
        probe = {}
        if spec["form"] == "hall_core":
            probe = {"exponent": spec["exponent"], "coercive": spec["coercive"] * In}
        elif spec["form"] == "current_transformer":
            probe = {k: spec[k] for k in ("exponent", "secondary_time_constant", "remanence")}
            probe["w_rated"] = 2 * math.pi * build.motor.frequency
        build.sensors.update(compress=spec["form"], compress_level=level, probe=probe)
        return {"level": level, **({"probe": probe} if probe else {})}


class SpeedSensorGain(Effect):
    name, unit = "speed_sensor_gain", "fraction"

    def _draw(self, rng, motor, form):
        ripple = float(rng.uniform(0.002, 0.01)) if form == "gain_ripple" else 0.0
        spec = {"size": signed(rng, 0.01, 0.05), "offset": float(rng.uniform(-0.005, 0.005) * motor.w_sync),
                "ripple": ripple, "ripple_phase": float(rng.uniform(0, 2 * np.pi))}
        if form == "tacho_filter":
            spec["time_constant"] = float(rng.uniform(1e-3, 5e-3))
        if form == "encoder_window":
            spec["gate_time"] = float(rng.uniform(1e-3, 5e-3))
        return spec

    def _apply(self, build, spec):
        build.sensors.update(speed_gain=1.0 + spec["size"], speed_offset=spec["offset"],
                             speed_ripple_rel=spec["ripple"], speed_ripple_phase=spec["ripple_phase"],
                             speed_lag=float(spec.get("time_constant", 0.0)),
                             speed_window=float(spec.get("gate_time", 0.0)))


class SensorOffset(Effect):
    name, unit = "sensor_offset", "A"

    def _draw(self, rng, motor, form):
        cur = [signed(rng, 0.05, 0.3) for _ in range(2)] if form != "voltage" else [0.0, 0.0]
        vol = [signed(rng, 0.5, 5.0) for _ in range(3)] if form != "current" else [0.0, 0.0, 0.0]
        size = max(abs(c) for c in cur) if form != "voltage" else max(abs(v) for v in vol)
        spec = {"size": size, "unit": "V" if form == "voltage" else "A", "current_offsets": cur,
                "voltage_offsets": vol}
        if form == "thermal_drift":
            drift = [signed(rng, 0.05, 0.2) for _ in range(2)]
            spec.update(drift=drift, time_constant=float(rng.uniform(0.3, 3.0)),
                        size=max(abs(c + d) for c, d in zip(cur, drift, strict=True)))
        return spec

    def _apply(self, build, spec):
        build.sensors.update(current_offset=tuple(spec["current_offsets"]),
                             voltage_offset=tuple(spec["voltage_offsets"]))
        if spec["form"] == "thermal_drift":
            build.sensors.update(offset_drift=tuple(spec["drift"]), offset_drift_tau=spec["time_constant"])


class ChannelDelay(Effect):
    name, unit = "channel_delay", "samples"

    def _draw(self, rng, motor, form):
        if form == "anti_alias":
            return {"size": float(rng.uniform(0.5, 2.0))}
        if form == "mux_skew":
            return {"size": float(rng.uniform(0.1, 0.3)), "order": [str(c) for c in rng.permutation(MUX_CHANNELS)]}
        return {"size": float(rng.uniform(0.1, 2.0))}

    def _apply(self, build, spec):
        if spec["form"] == "anti_alias":
            build.skew["filter"] = float(spec["size"])
        elif spec["form"] == "mux_skew":
            build.skew["mux"] = {"slot": float(spec["size"]), "order": list(spec["order"])}
        else:
            build.skew["current" if spec["form"] == "current_lag" else "voltage"] = float(spec["size"])

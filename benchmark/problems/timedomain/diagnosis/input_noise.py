"""The measured voltage's noise carried through the diagnosis's model into each channel's noise
level (:func:`benchmark.problems.timedomain.voltage_noise.with_propagated_voltage_noise`, which
says why): the adapter from the diagnosis's data and joint model."""

from __future__ import annotations

import copy
from dataclasses import replace

import numpy as np

from benchmark.problems.timedomain.diagnosis.fit import DiagnosisData, JointModel
from benchmark.problems.timedomain.voltage_noise import with_propagated_voltage_noise


def with_voltage_noise(data: DiagnosisData, model: JointModel, x: np.ndarray) -> tuple[DiagnosisData, dict | None]:
    """``data`` with each start-up channel's noise level raised by the measured voltage's noise
    carried through ``model`` at ``x`` (its base parameters), and a record of what was added
    (None when the voltages are not measured continuous signals)."""
    if not data.linear:
        return data, None
    slices = {ch: s for ch, s in data.channel_slices().items() if ch != "stop_speed"}

    def simulate(v_alpha, v_beta):
        driven = copy.copy(model)  # the same model, driven by these voltages
        driven.data = replace(data, v_alpha=v_alpha, v_beta=v_beta)
        y = driven.simulate(x[None, :])[0]
        return {ch: y[s] for ch, s in slices.items()}

    speed = data.meas[2] if data.has_speed else None
    noise, record = with_propagated_voltage_noise(data.noise, simulate, data.t, data.v_alpha, data.v_beta,
                                                  data.meas[0], data.meas[1], speed, data.supply_frequency)
    return replace(data, noise=noise), record

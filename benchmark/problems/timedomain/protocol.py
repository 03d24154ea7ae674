"""The start-up / free-stop experiment of Alonge et al. (the start-up/stop experiment), and the
amplitude-invariant Clarke transform.

The inverter applies switch states ``(aR, aS, aT)`` (1 = upper switch on); each state of the
six-step sequence is held for ``samples_per_state`` samples, the sequence is repeated
``cycles`` times (the start-up, about 1 s), then the zero vector ``111`` shorts the stator
and the rotor brakes electrically and then coasts to rest (the free stop).
A sinusoidal (direct-on-line) start is also available, for data that are not six-step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from benchmark.problems.timedomain.frames import clarke
from benchmark.problems.timedomain.motor import InductionMotor, coefficients
from benchmark.problems.timedomain.simulation import hold_is_linear, simulate_states

SIX_STEP_SEQUENCE = ((1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 1, 1), (0, 0, 1), (1, 0, 1))


def phase_voltages(switch_states: np.ndarray, dc_link_voltage: float) -> np.ndarray:
    """Phase voltages (V) of a two-level inverter for switch states of shape (n, 3)."""
    a = np.asarray(switch_states, dtype=float)
    total = a.sum(axis=1, keepdims=True)
    return (dc_link_voltage / 3.0) * (3.0 * a - total)


@dataclass(frozen=True)
class StartupStopTest:
    """Settings of the start-up / free-stop test.

    Attributes
    ----------
    dc_link_voltage : inverter DC-link voltage Ed, V.
    sample_time : sample time Ts, s (paper: 1/12000).
    samples_per_state : samples Nc each switch state is held (paper: 40, i.e. 50 Hz).
    cycles : repetitions N of the six-state sequence (start-up lasts 6*Nc*Ts*N).
    waveform : ``six_step`` (switch states, zero-order hold) or ``sinusoidal`` (a sampled
        balanced sine of the six-step's fundamental, interpolated linearly).
    stop_duration : longest free stop simulated, s (recording ends earlier at rest).
    stop_sample_time : sample time of the recorded stop speed, s.
    """

    dc_link_voltage: float = 300.0
    sample_time: float = 1.0 / 12000.0
    samples_per_state: int = 40
    cycles: int = 50
    waveform: str = "six_step"
    stop_duration: float = 30.0
    stop_sample_time: float = 1e-3

    @property
    def supply_frequency(self) -> float:
        """Fundamental frequency of the start-up supply, Hz."""
        return 1.0 / (6 * self.samples_per_state * self.sample_time)

    @property
    def n_startup(self) -> int:
        return 6 * self.samples_per_state * self.cycles

    @property
    def input_hold(self) -> str:
        return "zoh" if self.waveform == "six_step" else "linear"

    def startup_voltages(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Time (s) and stator voltages v_alpha, v_beta (V) of the start-up."""
        n = self.n_startup
        t = np.arange(n) * self.sample_time
        if self.waveform == "six_step":
            states = np.repeat(np.array(SIX_STEP_SEQUENCE), self.samples_per_state, axis=0)
            states = np.tile(states, (self.cycles, 1))
            v = phase_voltages(states, self.dc_link_voltage)
            v_a, v_b = clarke(v[:, 0], v[:, 1], v[:, 2])
        elif self.waveform == "sinusoidal":
            amplitude = 2.0 * self.dc_link_voltage / math.pi  # the six-step fundamental
            wt = 2.0 * math.pi * self.supply_frequency * t
            v_a, v_b = amplitude * np.cos(wt), amplitude * np.sin(wt)
        else:
            raise ValueError(f"waveform must be 'six_step' or 'sinusoidal', got {self.waveform!r}")
        return t, v_a, v_b


def run_startup_stop_extended(row: np.ndarray, test: StartupStopTest, substeps: int = 4) -> dict:
    """:func:`run_startup_stop` for an extended-model row (the plant with unmodelled effects)."""
    from benchmark.problems.timedomain.extended import N_STATES, simulate_extended

    t, v_a, v_b = test.startup_voltages()
    linear = hold_is_linear(test.input_hold)
    x = np.zeros(N_STATES)
    y = simulate_extended(row, v_a, v_b, linear, test.sample_time, substeps, x)
    startup = {"t": t, "v_alpha": v_a, "v_beta": v_b, "i_alpha": y[0], "i_beta": y[1], "speed": y[2]}
    # one more step with the last start-up voltage, then the stator is shorted (v = 0)
    simulate_extended(row, v_a[-1:].repeat(2), v_b[-1:].repeat(2), False, test.sample_time, substeps, x)
    n_stop = int(round(test.stop_duration / test.sample_time)) + 1
    zeros = np.zeros(n_stop)
    w_m = simulate_extended(row, zeros, zeros, False, test.sample_time, substeps, x)[2]
    return {"startup": startup, "stop": _stop_record(w_m, test)}


def _stop_record(w_m: np.ndarray, test: StartupStopTest) -> dict:
    """Decimate a simulated stop to ``stop_sample_time``, ending 0.5 s after rest."""
    n_stop = len(w_m)
    decimate = max(1, int(round(test.stop_sample_time / test.sample_time)))
    at_rest = np.flatnonzero(w_m <= 0.0)
    end = n_stop if len(at_rest) == 0 else min(n_stop, at_rest[0] + int(round(0.5 / test.sample_time)))
    idx = np.arange(0, end, decimate)
    return {"t": idx * test.sample_time, "speed": w_m[idx]}


def run_startup_stop(motor: InductionMotor, test: StartupStopTest, substeps: int = 4) -> dict:
    """Simulate the experiment on the reference plant (RK4 with ``substeps`` per sample).

    Returns ``{"startup": {t, v_alpha, v_beta, i_alpha, i_beta, speed}, "stop": {t, speed}}``;
    speeds are mechanical, rad/s; the stop record starts when the supply is removed and ends
    shortly after the rotor comes to rest (or at ``stop_duration``).
    """
    c = coefficients(motor.vector()[None, :], motor.p)[0]
    t, v_a, v_b = test.startup_voltages()
    linear = hold_is_linear(test.input_hold)
    x = simulate_states(c, v_a, v_b, linear, test.sample_time, substeps, np.zeros(5))
    startup = {
        "t": t,
        "v_alpha": v_a,
        "v_beta": v_b,
        "i_alpha": x[:, 0],
        "i_beta": x[:, 1],
        "speed": x[:, 4] / motor.p,
    }
    # The stop: the last start-up step is integrated with the start-up voltage, then v = 0.
    x_end = simulate_states(c, v_a[-1:].repeat(2), v_b[-1:].repeat(2), False, test.sample_time, substeps, x[-1])[-1]
    n_stop = int(round(test.stop_duration / test.sample_time)) + 1
    zeros = np.zeros(n_stop)
    xs = simulate_states(c, zeros, zeros, False, test.sample_time, substeps, x_end)
    return {"startup": startup, "stop": _stop_record(xs[:, 4] / motor.p, test)}

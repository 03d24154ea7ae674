"""Motor presets: T-circuit parameters, nameplate and default test settings, with sources.

Rated current and speed on each nameplate are computed from the circuit (the slip at which
the shaft delivers the rated power at rated voltage), so that nameplate and parameters agree.
Where a source gives no friction, ``fv`` is set for a friction loss of 0.7 % of rated power
at rated speed and ``fc`` to 0.5 % of rated torque (marked "estimated").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import cached_property

from synthetic.independent.machine import TMachine


@dataclass(frozen=True)
class Motor:
    """A motor preset.

    Parameters
    ----------
    name : preset name.
    machine : T-circuit parameters.
    rated_power : W.   voltage : rated line-line rms voltage, V.   frequency : rated, Hz.
    sample_rate : default sample rate of a start-up record, Hz.
    Ed : default DC link voltage of inverter tests, V.   Nc : default six-step samples per state.
    source : where the parameters come from.
    """

    name: str
    machine: TMachine
    rated_power: float
    voltage: float
    frequency: float
    sample_rate: float
    Ed: float
    Nc: int
    source: str

    @cached_property
    def rated(self) -> dict:
        return self.machine.rated_point(self.voltage, self.frequency, self.rated_power)

    @property
    def rated_current(self) -> float:
        """Rated current, A rms."""
        return self.rated["current"]

    @property
    def rated_current_peak(self) -> float:
        """Rated current amplitude (alpha-beta magnitude), A."""
        return math.sqrt(2) * self.rated["current"]

    @property
    def rated_torque(self) -> float:
        """N m."""
        return self.rated["torque"]

    @property
    def phase_peak(self) -> float:
        """Rated phase voltage amplitude, V."""
        return self.voltage * math.sqrt(2 / 3)

    @property
    def w_sync(self) -> float:
        """Synchronous mechanical speed at rated frequency, rad/s."""
        return 2 * math.pi * self.frequency / self.machine.p

    @property
    def psi_rated(self) -> float:
        """No-load magnetising flux amplitude at rated voltage, ``V/w * Lm/Ls``, Wb."""
        m = self.machine
        return self.phase_peak / (2 * math.pi * self.frequency) * m.Lm / m.Ls

    def nameplate(self) -> dict:
        """``rated_power`` W, ``voltage`` V line rms, ``current`` A rms, ``speed`` rpm, ``frequency`` Hz."""
        return {"rated_power": float(self.rated_power), "voltage": float(self.voltage),
                "current": round(self.rated_current, 2), "speed": round(self.rated["speed"]),
                "frequency": float(self.frequency)}

    def with_machine(self, machine: TMachine) -> Motor:
        return replace(self, machine=machine)


def _friction(P: float, f: float, p: int, slip: float = 0.04) -> tuple[float, float]:
    w = 2 * math.pi * f / p * (1 - slip)
    return 0.007 * P / w**2, 0.005 * P / w


def _preset(name, machine_fn, P, V, f, fs, Nc, source, *, p, J):
    fv, fc = _friction(P, f, p)
    return Motor(name, machine_fn(J, fv, fc), P, V, f, fs, round(V * math.pi / math.sqrt(6), 1), Nc, source)


PRESETS = {
    "paper_1kw": Motor(
        "paper_1kw",
        TMachine.from_referred(Rs=4.96434, Ls=0.1075, Le=0.01098, Rr=1.55618, J=0.00642, fv=0.00033, fc=0.04297, p=1),
        1000.0, 230.0, 50.0, 12000.0, 300.0, 40,
        "Alonge, D'Ippolito, Ferrante, Raimondi, IEE Proc. Control Theory Appl. 145(6), 1998, Table 1 "
        "(true values; referred, Lr = Ls, split Lls = Llr); 230 V nameplate voltage chosen to match a "
        "300 V DC link six-step fundamental"),
    "motulator_2k2": _preset(
        "motulator_2k2",
        lambda J, fv, fc: TMachine.from_inverse_gamma(Rs=3.7, RR=2.1, Lsgm=0.021, LM=0.224, p=2, J=J, fv=fv, fc=fc),
        2200.0, 400.0, 50.0, 12000.0, 40,
        "motulator (Aalto-Electric-Drives) 2.2-kW 400-V 50-Hz 4-pole example machine, inverse-Gamma "
        "R_s=3.7, R_R=2.1, L_sgm=0.021, L_M=0.224, J=0.015 (split Lls = Llr; fv, fc estimated)",
        p=2, J=0.015),
    "simulink_7k5": _preset(
        "simulink_7k5",
        lambda J, fv, fc: TMachine(Rs=0.7384, Lls=0.003045, Llr=0.003045, Lm=0.1241, Rr=0.7402, p=2, J=J, fv=fv, fc=fc),
        7500.0, 400.0, 50.0, 12000.0, 40,
        "MATLAB/Simscape asynchronous machine preset '10 HP (7.5 kW) 400 V 50 Hz 1440 rpm' (as also "
        "recorded in LBL Modelica Buildings IM_10HP_400V_50Hz); fv, fc estimated",
        p=2, J=0.0343),
    "simulink_5hp": _preset(
        "simulink_5hp",
        lambda J, fv, fc: TMachine(Rs=1.115, Lls=0.005974, Llr=0.005974, Lm=0.2037, Rr=1.083, p=2, J=J, fv=fv, fc=fc),
        3730.0, 460.0, 60.0, 10800.0, 30,
        "MATLAB/Simscape asynchronous machine preset '5 HP (3.7 kW) 460 V 60 Hz 1750 rpm' (as also "
        "recorded in LBL Modelica Buildings IM_5HP_460V_60Hz); fv, fc estimated",
        p=2, J=0.02),
    "fitzgerald_6pole": _preset(
        "fitzgerald_6pole",
        lambda J, fv, fc: TMachine.from_reactances(R1=0.294, X1=0.503, R2=0.144, X2=0.209, Xm=13.25, f=60.0,
                                                   p=3, J=J, fv=fv, fc=fc),
        7500.0, 220.0, 60.0, 10800.0, 30,
        "Fitzgerald, Kingsley, Umans, Electric Machinery (6th ed., Example 6.2): 7.5-kW 220-V 60-Hz "
        "6-pole motor, ohm per phase at 60 Hz; J (0.09 kg m^2) and fv, fc estimated",
        p=3, J=0.09),
}


def get_motor(name: str) -> Motor:
    try:
        return PRESETS[name]
    except KeyError:
        raise ValueError(f"unknown motor {name!r}; presets: {sorted(PRESETS)}") from None

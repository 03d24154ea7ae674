"""Synthetic motor test reports (``kind: loadtest``): the load points, no-load series, locked-rotor
test and DC resistance of a motor preset with ``kind: loadtest`` (``conf/motor/msl_18p5kw.yaml``),
with instrument noise and the rounding of instruments and reports, so that every claim on a test
report is first checked on data with a known truth.

The plant, per phase of the winding as connected: stator ``R1 + jX1``, rotor ``R2/s + jX2``, a
magnetising branch of constant core-loss conductance ``G_fe`` across ``jXm(psi)``, saturating
with the air-gap flux as ``Xm(psi) = Xm_rated (1 + c)/(1 + c (psi/psi_rated)^n)`` (``psi`` the
air-gap voltage over the frequency ratio; ``psi_rated`` that of the rated-voltage no-load point),
solved on :class:`benchmark.problems.admittance.sweep_circuit.SweepCircuit`. Copper resistances
follow the winding temperature of each test (234.5 C law). A reactance at supply frequency ``f``
is ``(f/f_rated) X``. Friction and windage (proportional to speed squared) and stray load loss
(proportional to the rotor current squared, so nil at no load as IEC 60034-2-1 assumes; the
Modelica model scales it with the stator current) load the shaft: a load point is the slip at which the shaft
delivers its power, a no-load point the slip at which it delivers none.

Measurement (``noise.loadtest_instruments`` scales the preset's ``instruments`` standard
deviations, 0 with ``noise=none``; ``noise.seed`` seeds them): voltage, current and power with
relative errors, speed with an absolute one, the power factor computed by the analyser from its
own readings, then everything rounded as ``rounding`` says (speed to 1 rpm, power factor to 3
digits, ...). ``test.format: report`` writes what a test report prints (line current, power
factor, speed, shaft power, efficiency; the nominal voltage in meta.yaml).

``truth.yaml``: the series-form circuit ``R1, X1, R2, X2, R0, X0`` at the reference temperature
and the rated-voltage no-load flux (``R0 + jX0 = 1/(G_fe - j/Xm_rated)``), and the plant.
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from omegaconf import OmegaConf
from scipy.optimize import brentq

from benchmark.core.errors import ConfigError
from benchmark.problems.admittance.circuit import copper_factor
from benchmark.problems.admittance.loadtest import load_loadtest, write_loadtest
from benchmark.problems.admittance.sweep_circuit import SweepCircuit

__all__ = ["make_dataset", "generate", "LoadTestPlant"]

SQ3 = float(np.sqrt(3.0))


def _plain(node):
    return OmegaConf.to_container(node, resolve=True) if OmegaConf.is_config(node) else node


@dataclass(frozen=True)
class LoadTestPlant:
    """The plant of a load-test preset (ohm per phase at rated frequency and ``theta_ref``)."""

    R1: float
    X1: float
    R2: float
    X2: float
    Xm: float
    G_fe: float
    fall: float
    exponent: float
    frequency: float
    pole_pairs: int
    theta_ref: float
    friction_w: float
    friction_rpm: float
    stray_w: float
    stray_current: float
    psi_rated: float = 1.0

    @classmethod
    def from_motor(cls, motor: dict) -> LoadTestPlant:
        p = motor["plant"]
        delta = motor["connection"] == "delta"
        V_ph = float(motor["voltage"]) / (1.0 if delta else SQ3)
        I_ph = float(motor["current"]) / (SQ3 if delta else 1.0)
        plant = cls(
            R1=float(p["R1"]), X1=float(p["X1"]), R2=float(p["R2"]), X2=float(p["X2"]), Xm=float(p["Xm"]),
            G_fe=float(p["core_loss_w"]) / (3.0 * float(p["core_loss_voltage"]) ** 2),
            fall=float(p["saturation_fall"]), exponent=float(p["saturation_exponent"]),
            frequency=float(motor["frequency"]), pole_pairs=int(motor["pole_pairs"]),
            theta_ref=float(motor["reference_temperature"]), friction_w=float(p["friction_windage_w"]),
            friction_rpm=float(p["friction_speed_rpm"]),
            stray_w=float(p["stray_load_w"]), stray_current=1.0,
        )
        # the rated flux: the air-gap voltage at rated voltage and slip 0 (where Xm = Xm_rated)
        Z0 = 1.0 / complex(plant.G_fe, -1.0 / plant.Xm)
        I0 = V_ph / (complex(plant.R1, plant.X1) + Z0)
        plant = cls(**{**plant.__dict__, "psi_rated": float(abs(V_ph - I0 * complex(plant.R1, plant.X1)))})
        # the rated rotor current: at rated stator current (the stray load loss's reference)
        s = brentq(lambda s: plant.point(s, V_ph, plant.theta_ref, rotor=True)["I"] - I_ph, 1e-6, 0.5)
        return cls(**{**plant.__dict__, "stray_current": plant.point(s, V_ph, plant.theta_ref, rotor=True)["I2"]})

    def truth(self) -> dict:
        Z0 = 1.0 / complex(self.G_fe, -1.0 / self.Xm)
        return {"R1": self.R1, "X1": self.X1, "R2": self.R2, "X2": self.X2, "R0": Z0.real, "X0": Z0.imag,
                "R1sigma": 0.0, "R2sigma": 0.0, "X3": 0.0, "R1_total": self.R1}

    def circuit(self, theta: float, k: float) -> SweepCircuit:
        """The circuit at winding temperature ``theta`` and frequency ratio ``k``."""
        c = self.fall / (1.0 - self.fall)
        Xu = self.Xm * (1.0 + c)

        def x0_of_e(E):
            return 1.0 / (1.0 + c * (np.asarray(E) / (k * self.psi_rated)) ** self.exponent)

        cu = float(copper_factor(theta, self.theta_ref))
        return SweepCircuit(R1t=self.R1 * cu, X1=k * self.X1, R2=self.R2 * cu, X2=k * self.X2, R0=0.0,
                            X0=k * Xu, x0_of_e=x0_of_e, gfe_of_e=lambda E: self.G_fe)

    def point(self, s: float, V: float, theta: float, k: float = 1.0, rotor: bool = False) -> dict:
        """Per-phase steady state at slip ``s``, phase voltage ``V``: current, powers, torque, speed
        (``rotor``: without the shaft losses, with the rotor current)."""
        Y, E, I1, I2 = self.circuit(theta, k).solve(np.array([s]), V)
        if rotor:
            return {"I": float(abs(I1[0])), "I2": float(abs(I2[0]))}
        P_ag = 3.0 * float(np.real(E * np.conj(I2))[0])
        n = 60.0 * k * self.frequency / self.pole_pairs * (1.0 - s)
        loss = self.friction_w * (n / self.friction_rpm) ** 2 + self.stray_w * (abs(I2[0]) / self.stray_current) ** 2
        return {"I": float(abs(I1[0])), "P": 3.0 * V * float(np.real(I1[0])), "speed": n,
                "shaft": (1.0 - s) * P_ag - (loss if s < 1 else 0.0),
                "torque_em": P_ag / (2 * np.pi * k * self.frequency / self.pole_pairs)}

    def at_shaft_power(self, P_shaft: float, V: float, theta: float) -> dict:
        s = brentq(lambda s: self.point(s, V, theta)["shaft"] - P_shaft, 1e-9, 0.3, xtol=1e-14)
        return self.point(s, V, theta)

    def locked(self, I_target: float, theta: float, k: float) -> tuple[float, dict]:
        V = brentq(lambda V: self.point(1.0, V, theta, k)["I"] - I_target, 1e-3, 1e4, xtol=1e-12)
        return V, self.point(1.0, V, theta, k)


class _Bench:
    """Instrument noise and rounding: ``measure(kind, x)``, with errors drawn from ``rng``."""

    def __init__(self, motor: dict, scale: float, seed: int):
        self.inst, self.rnd = motor["instruments"], motor["rounding"]
        self.scale, self.rng = float(scale), np.random.default_rng(seed)

    def noisy(self, kind: str, x, relative: bool = True):
        x = np.asarray(x, float)
        sd = self.scale * float(self.inst[kind])
        e = self.rng.normal(0.0, sd, x.shape)
        return x * (1.0 + e) if relative else x + e

    def round(self, kind: str, x):
        q = float(self.rnd[kind])
        return np.round(np.asarray(x, float) / q) * q + 0.0  # + 0.0: no '-0' in the tables


def _tables(motor: dict, plant: LoadTestPlant, bench: _Bench) -> dict[str, dict]:
    test, delta = motor["test"], motor["connection"] == "delta"
    V_line = float(motor["voltage"])
    to_ph = 1.0 if delta else SQ3
    temp = test["temperature"]
    out: dict[str, dict] = {}

    def electrical(V_ph, I_ph, P, n):
        V_m = bench.noisy("voltage", V_ph * to_ph)
        I_m = bench.noisy("current", I_ph * (SQ3 if delta else 1.0))
        P_m = bench.noisy("power", P) + bench.noisy("power_floor_w", np.zeros_like(P), relative=False)
        pf = np.clip(P_m / (SQ3 * V_m * I_m), 0.0, 1.0)
        speed = bench.noisy("speed_rpm", n, relative=False)
        return V_m, I_m, P_m, pf, speed

    def common(V_m, I_m, P_m, pf, theta):
        return {"line_voltage": bench.round("voltage", V_m), "line_current": bench.round("current", I_m),
                "power": bench.round("power", P_m), "power_factor": bench.round("power_factor", pf),
                "temperature": bench.round("temperature", bench.noisy("temperature", theta, relative=False))}

    if "load" in test["tables"]:
        theta = float(temp["load"])
        pts = [plant.at_shaft_power(float(P), V_line / to_ph, theta) for P in test["load_shaft_power"]]
        arr = {k: np.array([p[k] for p in pts]) for k in pts[0]}
        V_m, I_m, P_m, pf, speed = electrical(np.full(len(pts), V_line / to_ph), arr["I"], arr["P"], arr["speed"])
        w = arr["speed"] * 2 * np.pi / 60.0
        T_m = bench.noisy("torque", np.where(w > 0, arr["shaft"] / w, 0.0))
        shaft = bench.round("shaft_power", T_m * speed * 2 * np.pi / 60.0)
        if test["format"] == "report":
            out["load"] = {"shaft_power": shaft, "line_current": bench.round("current", I_m),
                           "speed_rpm": bench.round("speed_rpm", speed),
                           "power_factor": bench.round("power_factor", pf),
                           "efficiency": bench.round("efficiency", shaft / P_m)}
        else:
            out["load"] = common(V_m, I_m, P_m, pf, np.full(len(pts), theta)) | {
                "speed_rpm": bench.round("speed_rpm", speed), "torque": bench.round("torque", T_m),
                "shaft_power": shaft}
    if "noload" in test["tables"]:
        theta = float(temp["noload"])
        V_ph = np.asarray(test["noload_voltages"], float) / to_ph
        pts = [plant.at_shaft_power(0.0, v, theta) for v in V_ph]
        V_m, I_m, P_m, pf, speed = electrical(V_ph, np.array([p["I"] for p in pts]),
                                              np.array([p["P"] for p in pts]), np.array([p["speed"] for p in pts]))
        out["noload"] = common(V_m, I_m, P_m, pf, np.full(len(pts), theta)) | {
            "speed_rpm": bench.round("speed_rpm", speed)}
    if "locked" in test["tables"]:
        theta, f_lr = float(temp["locked"]), float(test["locked_frequency"])
        k = f_lr / plant.frequency
        I_ph = np.asarray(test["locked_currents"], float) / (SQ3 if delta else 1.0)
        pts = [plant.locked(i, theta, k) for i in I_ph]
        V_m, I_m, P_m, pf, _ = electrical(np.array([v for v, _ in pts]), I_ph, np.array([p["P"] for _, p in pts]),
                                          np.zeros(len(pts)))
        out["locked"] = common(V_m, I_m, P_m, pf, np.full(len(pts), theta)) | {
            "frequency": np.full(len(pts), f_lr),
            "torque": bench.round("torque", bench.noisy("torque", [p["torque_em"] for _, p in pts]))}
    return out


def _meta(motor: dict, plant: LoadTestPlant, bench: _Bench, seed: int) -> dict:
    test = motor["test"]
    meta = {"frequency": plant.frequency, "pole_pairs": plant.pole_pairs, "connection": motor["connection"],
            "voltage": float(motor["voltage"]),
            "description": f"synthetic test report of motor {motor['name']} ({', '.join(test['tables'])}; "
                           f"format {test['format']}; instrument noise x{bench.scale:g}, seed {seed})"}
    if test["format"] == "bench":
        meta["reference_temperature"] = plant.theta_ref
    if test.get("dc_resistance", True):
        theta = float(test["temperature"]["dc"])
        R_ph = plant.R1 * float(copper_factor(theta, plant.theta_ref))
        R_tt = R_ph * (2.0 / 3.0 if motor["connection"] == "delta" else 2.0)
        value = float(bench.round("dc_resistance", bench.noisy("dc_resistance", R_tt)))
        meta["stator_dc_resistance"] = {"value": value, "temperature": theta, "between": "terminals"}
    return meta


def _compose(run):
    motor = _plain(run["motor"])
    missing = [k for k in ("plant", "test", "instruments", "rounding", "connection", "voltage", "current")
               if k not in motor]
    if missing:
        raise ConfigError(f"motor.{missing[0]}: a kind: loadtest preset needs {missing}")
    noise = _plain(run.get("noise") or {})
    scale = float(noise.get("loadtest_instruments", 0.0) or 0.0)
    seed = int(noise.get("seed", 0) or 0)
    plant = LoadTestPlant.from_motor(motor)
    bench = _Bench(motor, scale, seed)
    tables = _tables(motor, plant, bench)
    truth = {"kind": "loadtest", "motor": motor["name"], "model": "6-parameter",
             "reference_temperature": plant.theta_ref, "parameters": plant.truth(),
             "plant": {k: v for k, v in plant.__dict__.items()},
             "noise": {"loadtest_instruments": scale, "seed": seed}}
    return _meta(motor, plant, bench, seed), tables, truth


def generate(run, outdir: Path) -> Path:
    """Write the test report of the run's ``kind: loadtest`` motor preset to ``outdir``."""
    meta, tables, truth = _compose(run)
    return write_loadtest(Path(outdir), meta, tables, truth)


def make_dataset(run):
    """The report as the problem reads it (written to a temporary folder and loaded: one
    conversion path for synthetic and measured reports) and its truth document."""
    meta, tables, truth = _compose(run)
    with tempfile.TemporaryDirectory() as tmp:
        data = load_loadtest(write_loadtest(Path(tmp), meta, tables))
    data.source = "synthetic"
    return data, truth

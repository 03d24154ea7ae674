"""Synthetic Lindsay-Barton slip sweeps (docs/data_format.md, kind ``admittance``).

The bench: the machine is held by a speed-controlled work machine and ramped at
``test.ramp_rpm_per_s`` from ``speed_start_rpm`` to ``speed_stop_rpm`` at constant phase voltage,
with a reading of G, B (and the electromagnetic torque) every ``speed_step_rpm``; optionally more
voltage levels (one sweep each) and a down-sweep after each up-sweep. The stator DC resistance is
measured at ``t = 0`` (machine at the start speed, supply about to be connected; the first reading
follows ``settle_s`` later) and ``dc_after_delay_s`` after the last reading (supply off).

Warming (``test.warming``): the one-body thermal model of :class:`benchmark.problems.admittance.circuit.ThermalModel`
is integrated along the whole session on a fine time grid, heated by all electrical losses
(``P_in - P_mech``: stator and rotor copper and core losses; in braking the shaft power too), with the
copper resistances R1, R2 following the temperature. Between sweeps without a down-sweep the supply
is off and the speed returns to the start unexcited. The data carry the DC resistances, their times,
the winding temperature at the first DC measurement, and the cooling rates ``K/C`` (what two cooling
curves give; the capacitance, i.e. the heating scale, stays unknown to the identification).

Noise (``run['noise']['admittance_fraction']``): white Gaussian noise of standard deviation ``fraction *
full_scale_admittance`` on G and on B, and ``fraction * full_scale_torque`` on the torque, from
``numpy.random.default_rng(noise.seed)``; with ``noise.admittance_reading_fraction`` also noise of standard
deviation ``reading_fraction * |Y|`` on G and on B of each reading (an instrument's error as a share of its
reading), drawn after the full-scale noise. DC resistances are exact (a four-wire measurement).

Unmodelled effects (``run.effects``, ``effect_size``, ``effect_form``; the catalogue of
:mod:`benchmark.problems.admittance.effects`): with ``effects`` named, the data hold exactly those effects on the
preset's bare 6-parameter machine (its ``R1sigma``, ``R2sigma``, ``X3`` and its warming, which are catalogue
effects themselves, are removed first); ``effects=[none]`` is the bare machine. The sweep is then computed on
the generalised circuit :class:`benchmark.problems.admittance.sweep_circuit.SweepCircuit` (torque from the
air-gap power),
and ``temperature_drift`` turns the warming on with the heating scale set to give its temperature rise.
Without ``effects`` the preset is used as it is (Lindsay and Barton's model F, warming on).

``truth.yaml`` holds the parameters at the reference temperature, the temperatures, the noise, and the
injected effects with their sizes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from omegaconf import OmegaConf

from benchmark.core.errors import ConfigError
from benchmark.problems.admittance.circuit import (
    CircuitParameters,
    ThermalModel,
    copper_factor,
    operating_point,
    slip_from_speed,
    synchronous_speed_rpm,
)
from benchmark.problems.admittance.data import AdmittanceData, write_admittance

__all__ = ["make_dataset", "generate", "parameters_from_config", "nice_ceiling"]

FINE_STEP_S = 0.05


def _sel(run, key, default=None):
    """``run[a][b]...`` for the dotted ``key`` of the resolved run configuration (a plain
    mapping), or ``default`` when a level is missing or the value is null."""
    v = run
    for part in key.split("."):
        if not hasattr(v, "get"):
            return default
        v = v.get(part)
        if v is None:
            return default
    return v


def parameters_from_config(run) -> CircuitParameters:
    """The true circuit (ohm at the test frequency, at ``motor.reference_temperature``)."""
    p = _sel(run, "motor.parameters")
    if p is None:
        raise ConfigError(
            "motor.parameters: the admittance motor preset must give the circuit parameters "
            "R1, X1, R2, X2, R0, X0 (and R1sigma, R2sigma, X3 for the 8-parameter machine)"
        )
    try:
        return CircuitParameters.from_mapping(OmegaConf.to_container(p) if OmegaConf.is_config(p) else p)
    except (KeyError, TypeError, ValueError) as exc:
        raise ConfigError(f"motor.parameters: {exc}") from None


def nice_ceiling(x: float) -> float:
    """Smallest of 1, 1.5, 2, 2.5, 3, 4, 5, 6, 8, 10 x 10^k not below ``x``: an instrument range."""
    k = np.floor(np.log10(x))
    for m in (1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0):
        if m * 10**k >= x * (1 - 1e-12):
            return float(m * 10**k)
    return float(10 ** (k + 1))


def _schedule(test, voltages):
    """Segments ``(t0, t1, n0, n1, V)`` (V = 0: supply off) and readings ``(t, n, V, sweep)``."""
    n_a, n_b = float(test["speed_start_rpm"]), float(test["speed_stop_rpm"])
    step, ramp = float(test["speed_step_rpm"]), float(test["ramp_rpm_per_s"])
    settle = float(test["settle_s"])
    if ramp <= 0 or step <= 0:
        raise ConfigError("motor.test.ramp_rpm_per_s and speed_step_rpm: must be positive")
    if n_b <= n_a:
        raise ConfigError(f"motor.test.speed_stop_rpm: must exceed speed_start_rpm ({n_b} <= {n_a})")
    up = np.arange(n_a, n_b + step / 2, step)
    down = up[::-1][1:]
    T = (n_b - n_a) / ramp
    segs, reads = [], []
    t, sweep = 0.0, 0
    for k, V in enumerate(voltages):
        if k > 0 and not test["down_sweep"]:
            segs.append((t, t + T, n_b, n_a, 0.0))  # back to the start, unexcited
            t += T
        segs.append((t, t + settle, n_a, n_a, V))
        t += settle
        segs.append((t, t + T, n_a, n_b, V))
        reads += [(t + (n - n_a) / ramp, n, V, sweep) for n in up]
        t += T
        sweep += 1
        if test["down_sweep"]:
            segs.append((t, t + T, n_b, n_a, V))
            reads += [(t + (n_b - n) / ramp, n, V, sweep) for n in down]
            t += T
            sweep += 1
    return segs, reads, t


def _effects_plant(run, params, test, thermal_cfg, voltages, f, p) -> dict | None:
    """The plant with the unmodelled effects of ``run.effects`` injected (the hook of
    :mod:`benchmark.problems.admittance.effects`), or None when no effect is named.

    With ``effects`` given, the data hold exactly the named effects: the preset's own catalogue
    terms (``R1sigma``, ``R2sigma``, ``X3``: ``leakage_core_loss``, ``leakage_saturation``; the
    warming: ``temperature_drift``) are removed first, leaving the 6-parameter machine, and
    each named effect is added at ``effect_size[name]`` (default: the geometric middle of its
    realistic range) with ``effect_form[name]`` varying its form. ``effects=[none]`` is the bare
    6-parameter machine without warming."""
    from benchmark.core.effects import load_effects
    from benchmark.problems.admittance.sweep_circuit import SweepCircuit, SweepContext

    names = [str(n) for n in (_sel(run, "effects", []) or [])]
    if not names:
        return None
    names = [n for n in names if n != "none"]
    sizes = _sel(run, "effect_size", {}) or {}
    forms = _sel(run, "effect_form", {}) or {}
    sizes = OmegaConf.to_container(sizes) if OmegaConf.is_config(sizes) else dict(sizes)
    forms = OmegaConf.to_container(forms) if OmegaConf.is_config(forms) else dict(forms)
    unknown = sorted(set(sizes) - set(names)) + sorted(set(forms) - set(names))
    if unknown:
        raise ConfigError(f"effect_size/effect_form: {unknown} not among effects={names}")
    catalogue = load_effects("admittance", names=names) if names else {}
    bare = CircuitParameters(**(params.to_dict() | {"R1sigma": 0.0, "R2sigma": 0.0, "X3": 0.0}))
    test = dict(test) | {"warming": False}
    thermal_cfg = dict(thermal_cfg)
    # the sweep's own scales: no-load air-gap voltage and standstill current at the top level
    V_top = max(voltages)
    op0 = operating_point(bare, np.array([0.0, 1.0]), V_top, f, p)
    E_top = float(np.abs(V_top - op0.I1[0] * complex(bare.R1_total, bare.X1)))
    ctx = SweepContext(E_top=E_top, I_stall=float(np.abs(op0.I1[1])), frequency=f)
    circuit = SweepCircuit.from_parameters(bare.to_dict())
    injected, target_rise = [], None
    for name in names:
        eff = catalogue[name]
        lo, hi = eff.realistic
        size = float(sizes.get(name, np.sqrt(lo * hi)))
        form = eff.form_of(forms.get(name))
        try:
            circuit = eff.plant(circuit, size, ctx, form)
        except ValueError as exc:
            raise ConfigError(str(exc)) from None
        session = eff.session(size, form)
        if session.get("warming"):
            test["warming"] = True
            target_rise = session["target_rise_K"]
            if not session.get("cooling", True):
                thermal_cfg |= {"conductance_standstill": 0.0, "conductance_at_speed": 0.0}
        injected.append({"name": name, "size": size, "size_name": eff.size_name, "unit": eff.size_unit, "form": form})
    return {
        "params": bare,
        "test": test,
        "thermal": thermal_cfg,
        "circuit": circuit,
        "injected": injected,
        "target_rise_K": target_rise,
        "scales": {"E_top_V": E_top, "I_stall_A": ctx.I_stall},
    }


def _thermal_for_rise(session_temperatures, thermal: ThermalModel, theta0: float, rise: float) -> ThermalModel:
    """The thermal model with its capacitance scaled so that the winding temperature rises by
    ``rise`` K from the first reading to the hottest (secant steps on the heating scale 1/C)."""
    from dataclasses import replace

    def achieved(th):
        theta, _ = session_temperatures(th)
        return float(theta.max() - theta[0])

    h, r = 1.0 / thermal.capacitance, achieved(thermal)
    for _ in range(3):
        if r <= 0:
            break
        h_new = h * rise / r
        thermal = replace(thermal, capacitance=1.0 / h_new)
        r_new = achieved(thermal)
        h, r = h_new, r_new
        if abs(r - rise) <= 1e-3 * rise:
            break
    return thermal


def make_dataset(run) -> tuple[AdmittanceData, dict]:
    """The sweep data set and its truth document for the composed config (motor preset + noise);
    a ``kind: loadtest`` preset makes a test report instead (:mod:`synthetic.loadtest`)."""
    if _sel(run, "motor.kind") == "loadtest":
        from synthetic.loadtest import make_dataset as make_report

        return make_report(run)
    params = parameters_from_config(run)
    f = float(_sel(run, "motor.frequency", 60.0))
    p = int(_sel(run, "motor.pole_pairs", 2))
    theta_ref = float(_sel(run, "motor.reference_temperature", 50.0))
    test_defaults = {
        "voltages": [30.2],
        "speed_start_rpm": -1800.0,
        "speed_stop_rpm": 2400.0,
        "speed_step_rpm": 100.0,
        "ramp_rpm_per_s": 25.0,
        "down_sweep": False,
        "settle_s": 20.0,
        "dc_after_delay_s": 5.0,
        "warming": True,
        "full_scale_admittance": None,
        "record_torque": True,
    }
    test_cfg = _sel(run, "motor.test", {})
    test_cfg = OmegaConf.to_container(test_cfg) if OmegaConf.is_config(test_cfg) else dict(test_cfg)
    unknown = set(test_cfg) - set(test_defaults)
    if unknown:
        raise ConfigError(f"motor.test: unknown key(s) {sorted(unknown)}; known: {sorted(test_defaults)}")
    test = test_defaults | test_cfg
    voltages = [float(v) for v in np.atleast_1d(test["voltages"])]
    if not voltages or min(voltages) <= 0:
        raise ConfigError(f"motor.test.voltages: positive phase voltages (V RMS) needed, got {voltages}")

    th = _sel(run, "motor.thermal", {})
    th = OmegaConf.to_container(th) if OmegaConf.is_config(th) else dict(th)
    plant = _effects_plant(run, params, test, th, voltages, f, p)
    if plant is not None:
        params, test, th = plant["params"], plant["test"], plant["thermal"]
    warming = bool(test["warming"])
    if warming:
        try:
            thermal = ThermalModel(
                capacitance=float(th["capacitance"]),
                conductance_standstill=float(th["conductance_standstill"]),
                conductance_at_speed=float(th["conductance_at_speed"]),
                conductance_speed_rpm=float(th["conductance_speed_rpm"]),
                ambient_temperature=float(th["ambient_temperature"]),
            )
        except KeyError as exc:
            raise ConfigError(f"motor.thermal.{exc.args[0]}: needed when motor.test.warming is true") from None
    theta0 = float(th.get("initial_temperature", theta_ref))

    segs, reads, t_end = _schedule(test, voltages)
    t_read = np.array([r[0] for r in reads])
    n_read = np.array([r[1] for r in reads])
    v_read = np.array([r[2] for r in reads])
    sweep = np.array([r[3] for r in reads], int)
    t_after = t_end + float(test["dc_after_delay_s"])

    # temperature along the session: exact exponential steps, losses at the step midpoint
    def session_temperatures(thermal):
        grid = [0.0]
        for t0, t1, *_ in segs:
            m = max(1, int(np.ceil((t1 - t0) / FINE_STEP_S)))
            grid += list(np.linspace(t0, t1, m + 1)[1:])
        grid = np.unique(np.concatenate([grid, t_read, [t_after]]))
        theta = np.empty_like(grid)
        theta[0] = theta0
        starts = np.array([sg[0] for sg in segs])
        for i in range(len(grid) - 1):
            tm = 0.5 * (grid[i] + grid[i + 1])
            j = int(np.searchsorted(starts, tm, side="right")) - 1
            if j < len(segs) and tm <= segs[j][1]:
                t0, t1, n0, n1, V = segs[j]
                n = n0 + (n1 - n0) * (tm - t0) / (t1 - t0) if t1 > t0 else n0
            else:  # after the last reading: supply off, speed held
                n, V = segs[-1][3], 0.0
            P = 0.0
            if V > 0:
                op = operating_point(params.at_temperature(theta[i], theta_ref), slip_from_speed(n, f, p), V, f, p)
                P = float(op.P_in - op.P_mech)
            theta[i + 1] = thermal.step(theta[i], P, n, grid[i + 1] - grid[i])
        return np.interp(t_read, grid, theta), float(np.interp(t_after, grid, theta))

    if warming:
        if plant is not None and plant["target_rise_K"] is not None:
            thermal = _thermal_for_rise(session_temperatures, thermal, theta0, plant["target_rise_K"])
        theta_read, theta_after = session_temperatures(thermal)
    else:
        theta_read = np.full(len(t_read), theta0)
        theta_after = theta0

    s = slip_from_speed(n_read, f, p)
    k = copper_factor(theta_read, theta_ref)
    warm = CircuitParameters(**(params.to_dict() | {"R1": params.R1 * k, "R2": params.R2 * k}))
    if plant is None:
        op = operating_point(warm, s, v_read, f, p)
        Y, T = op.Y, op.torque
    else:
        Y, E, _, I2 = plant["circuit"].with_(copper=k).solve(s, v_read)
        T = 3.0 * np.real(E * np.conj(I2)) / (2.0 * np.pi * f / p)
    fs = test["full_scale_admittance"]
    fs = float(fs) if fs is not None else nice_ceiling(float(np.max(np.abs(Y))))
    fs_T = nice_ceiling(float(np.max(np.abs(T))))

    frac = float(_sel(run, "noise.admittance_fraction", 0.0))
    seed = int(_sel(run, "noise.seed", 0))
    rng = np.random.default_rng(seed)
    G = Y.real + (rng.normal(0.0, frac * fs, len(s)) if frac > 0 else 0.0)
    B = Y.imag + (rng.normal(0.0, frac * fs, len(s)) if frac > 0 else 0.0)
    torque = T + (rng.normal(0.0, frac * fs_T, len(s)) if frac > 0 else 0.0)
    reading_frac = float(_sel(run, "noise.admittance_reading_fraction", 0.0))
    if reading_frac > 0:
        G = G + rng.normal(0.0, 1.0, len(s)) * reading_frac * np.abs(Y)
        B = B + rng.normal(0.0, 1.0, len(s)) * reading_frac * np.abs(Y)

    # the DC readings see the stator copper only (R1, not R1sigma)
    R_dc = (
        float(params.R1 * copper_factor(theta0, theta_ref)),
        float(params.R1 * copper_factor(theta_after, theta_ref)),
    )
    data = AdmittanceData(
        frequency=f,
        pole_pairs=p,
        slip=s,
        G=np.asarray(G, float),
        B=np.asarray(B, float),
        voltage=v_read,
        time=t_read,
        torque=np.asarray(torque, float) if test["record_torque"] else None,
        sweep=sweep,
        full_scale_admittance=fs,
        full_scale_torque=fs_T,
        stator_dc_resistance=R_dc,
        dc_resistance_time=(0.0, t_after),
        winding_temperature_before=theta0,
        reference_temperature=theta_ref,
        thermal=(
            {
                "ambient_temperature": thermal.ambient_temperature,
                "cooling_rate_standstill": thermal.cooling_rate(0.0),
                "cooling_rate_at_speed": thermal.cooling_rate(thermal.conductance_speed_rpm),
                "cooling_rate_speed_rpm": thermal.conductance_speed_rpm,
            }
            if warming
            else None
        ),
        supply_off=[(t0, t1) for t0, t1, _, _, V in segs if V == 0] or None,
        source="synthetic",
        description=f"synthetic Lindsay-Barton sweep, motor {_sel(run, 'motor.name', '?')}, "
        f"{len(voltages)} voltage level(s), down-sweep {bool(test['down_sweep'])}",
    )
    truth = {
        "kind": "admittance",
        "motor": str(_sel(run, "motor.name", "?")),
        "model": "6-parameter" if params.is_six_parameter else "8-parameter",
        "reference_temperature": theta_ref,
        "parameters": params.to_dict() | {"R1_total": params.R1_total},
        "temperature": {
            "before": theta0,
            "after": theta_after,
            "first_reading": float(theta_read[0]),
            "last_reading": float(theta_read[-1]),
        },
        "noise": {
            "admittance_fraction": frac,
            "admittance_reading_fraction": reading_frac,
            "seed": seed,
            "full_scale_admittance": fs,
            "full_scale_torque": fs_T,
        },
        "effects": {
            "temperature_drift": {"rise_C": float(theta_read.max() - theta0)} if warming else None,
            "leakage_core_loss": {"R1sigma": params.R1sigma, "R2sigma": params.R2sigma},
            "leakage_saturation": {"X3": params.X3},
        }
        if plant is None
        else plant["injected"],
        "synchronous_speed_rpm": synchronous_speed_rpm(f, p),
    }
    if plant is not None:
        truth["effect_scales"] = plant["scales"]
    return data, truth


def generate(run, outdir: Path) -> Path:
    """Write the data set of :func:`make_dataset` (section 7 format + truth.yaml) to ``outdir``."""
    if _sel(run, "motor.kind") == "loadtest":
        from synthetic.loadtest import generate as write_report

        return write_report(run, outdir)
    data, truth = make_dataset(run)
    return write_admittance(Path(outdir), data, truth=truth)

"""Start-up data sets simulated by motulator, a third-party drive simulator.

motulator (Aalto University, https://github.com/Aalto-Electric-Drives/motulator) is an
optional dependency (``pip install -e .[validation]``, pinned to the 0.5 series). It models
the induction machine with the Gamma-equivalent circuit: stator inductance ``L_s`` (on the
stator side, optionally saturating with the stator flux), leakage ``L_ell`` and resistance
``R_r`` on the rotor side. Because the simulator, its machine parametrisation and its ODE
solver (scipy ``solve_ivp``, RK45, one call per sample period) are not the project's, a
parameter set identified on these data checks the project's model and referral end to end.

Referral to the project's parametrisation (``Lr = Ls``): the quantities a stator-side
experiment can see are ``Rs``, the stator self-inductance ``Ls``, the transient inductance
``Le = sigma*Ls`` and the rotor time constant ``tau_r``. In the Gamma model they are
``Ls = L_s``, ``Le = L_s*L_ell/(L_s + L_ell)`` and ``tau_r = (L_s + L_ell)/R_r``; the
project's rotor resistance is ``Rr = Lr/tau_r = L_s*R_r/(L_s + L_ell)``. Conversely
``L_ell = Le*Ls/(Ls - Le)`` and ``R_r = Rr*Ls/(Ls - Le)`` (:func:`gamma_from_project`).

Scenarios: ``dol`` (a stiff three-phase sine source switched on at ``t = 0``; an ideal
voltage source replaces motulator's converter; ``input_hold: linear``), ``six_step`` (the
Alonge et al. switch sequence ``100, 110, 010, 011, 001, 101`` from an ideal inverter,
``input_hold: zoh``) and ``pwm`` (an open-loop sine reference, min-max zero-sequence
injection, motulator's carrier comparison with ideal switches and the carrier half-period
equal to the sample time; the record holds the per-sample average voltage, ``zoh``).

Effects motulator provides: ``main_saturation`` (its saturable Gamma model,
``L_s(psi) = L_u/(1 + (psi/psi_k)**S)``), ``two_mass`` (its two-mass mechanics, speed
sensed on the load side) and ``load_torque``. Coulomb friction is motulator's speed-dependent
friction coefficient ``B_L(|w|) = fv + fc/max(|w|, eps)`` (``eps`` = :data:`COULOMB_SMOOTHING`).
Held-out forms (for scoring only, :mod:`synthetic.motulator_effects`; option ``form``):
``main_saturation`` ``steel_gap`` (gap plus M800-50A iron), ``two_mass`` ``slip_clutch``
(a torque limiter slipping in series with the coupling; ``elastomer``, a progressive coupling, is retired
from them), ``load_torque`` ``battery_charger`` (a permanent-magnet generator charging a battery through diodes:
no torque below its cut-in speed; ``eddy_brake``, an eddy-current brake with its excitation's rise,
and ``dc_generator``, a DC generator with its armature circuit as an extra state, are retired from them).
"""

from __future__ import annotations

import importlib.metadata
import math
from pathlib import Path

import numpy as np
import yaml

from synthetic.motulator_effects import (
    COULOMB_SMOOTHING,
    EFFECTS,  # noqa: F401 (re-exported: the effects this source offers)
    M800_50A,
    effect_specs,
    mechanics,
    steel_gap_inductance,
)

SCENARIOS = ("dol", "six_step", "pwm")
PARAMETER_NAMES = ("Rs", "Ls", "Le", "Rr", "J", "fv", "fc")
SIX_STEP_SEQUENCE = ((1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 1, 1), (0, 0, 1), (1, 0, 1))
#: Counter levels of motulator's carrier comparison (duty ratios are quantised to these).
PWM_LEVELS = 2**12
INSTALL_HINT = "motulator is not installed: pip install -e .[validation]"
_CACHE: dict = {}


def load_motulator():
    """Import motulator's drive model lazily; a clear ImportError when it is missing."""
    if "model" not in _CACHE:
        try:
            from motulator.common.model import CarrierComparison, Delay, Subsystem
            from motulator.common.utils import abc2complex, complex2abc
            from motulator.drive import model
            from motulator.drive.utils import InductionMachinePars, TwoMassMechanicalSystemPars
        except ImportError as exc:
            raise ImportError(INSTALL_HINT) from exc
        _CACHE.update(model=model, Delay=Delay, Subsystem=Subsystem, CarrierComparison=CarrierComparison,
                      abc2complex=abc2complex, complex2abc=complex2abc, ImPars=InductionMachinePars,
                      TwoMassPars=TwoMassMechanicalSystemPars,
                      version=importlib.metadata.version("motulator"))
    return _CACHE


# -- parametrisations ------------------------------------------------------------------

def gamma_from_project(p: dict) -> dict:
    """Gamma-model parameters (``R_s, R_r, L_ell, L_s``; ohm, H) of project parameters (``Lr = Ls``)."""
    Ls, Le = float(p["Ls"]), float(p["Le"])
    if not 0 < Le < Ls:
        raise ValueError(f"need 0 < Le < Ls, got Le={Le}, Ls={Ls}")
    return {"R_s": float(p["Rs"]), "R_r": float(p["Rr"]) * Ls / (Ls - Le), "L_ell": Le * Ls / (Ls - Le), "L_s": Ls}


def project_from_gamma(R_s: float, R_r: float, L_ell: float, L_s: float) -> dict:
    """Project parameters ``Rs, Ls, Le, Rr`` (ohm, H; ``Lr = Ls``) of a Gamma model."""
    return {"Rs": R_s, "Ls": L_s, "Le": L_s * L_ell / (L_s + L_ell), "Rr": L_s * R_r / (L_s + L_ell)}


def project_from_inverse_gamma(R_s: float, R_R: float, L_sgm: float, L_M: float) -> dict:
    """Project parameters of an inverse-Gamma model (``Ls = L_M + L_sgm``, ``Le = L_sgm``, ``tau_r = L_M/R_R``)."""
    Ls = L_M + L_sgm
    return {"Rs": R_s, "Ls": Ls, "Le": L_sgm, "Rr": Ls * R_R / L_M}


def project_from_t_model(Rs: float, Rr: float, Lls: float, Llr: float, Lm: float) -> dict:
    """Project parameters of a T model (stator and rotor leakage ``Lls, Llr``, magnetising ``Lm``)."""
    Ls, Lr = Lls + Lm, Llr + Lm
    return {"Rs": Rs, "Ls": Ls, "Le": Ls - Lm**2 / Lr, "Rr": Rr * Ls / Lr}


# -- motor description -----------------------------------------------------------------

def _motor(motor: dict) -> dict:
    """Flatten a motor description: ``parameters`` (or the seven names at top level),
    ``pole_pairs``, ``voltage`` (V line-line rms), ``frequency`` (Hz), optional
    ``dc_link_voltage`` (V), ``rated_torque`` (N m) or ``rated_power`` (W)."""
    src = motor.get("parameters", motor)
    try:
        par = {n: float(src[n]) for n in PARAMETER_NAMES}
        p = int(motor["pole_pairs"])
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"motor: need {list(PARAMETER_NAMES)} and pole_pairs ({exc!r})") from None
    if p < 1 or min(par[n] for n in ("Rs", "Ls", "Le", "Rr", "J")) <= 0 or par["fv"] < 0 or par["fc"] < 0:
        raise ValueError(f"motor: parameters must be positive (friction >= 0), got {par}, pole_pairs={p}")
    m = {"par": par, "p": p, "f": float(motor.get("frequency", 50.0)), "name": motor.get("name", "motor")}
    for key in ("voltage", "dc_link_voltage", "rated_torque", "rated_power"):
        m[key] = float(motor[key]) if motor.get(key) is not None else None
    if m["rated_torque"] is None and m["rated_power"]:
        m["rated_torque"] = m["rated_power"] / (0.97 * 2 * np.pi * m["f"] / p)
    return m


def _excitation(m: dict, scenario: str, Ts: float, n: int) -> dict:
    """Supply of a scenario: voltage function or duty/switch schedule, hold, frequency, flux."""
    f, w = m["f"], 2 * np.pi * m["f"]
    U, Ed = m["voltage"], m["dc_link_voltage"]
    if scenario == "six_step":
        if Ed is None:
            if U is None:
                raise ValueError("six_step: give the motor's voltage or dc_link_voltage")
            Ed = 0.5 * np.pi * np.sqrt(2 / 3) * U  # six-step fundamental = rated voltage
        nc = max(1, round(1 / (6 * f * Ts)))
        k = (np.arange(n) // nc) % 6
        duty = np.asarray(SIX_STEP_SEQUENCE, dtype=float)[k]
        return {"duty": duty, "Ed": Ed, "hold": "zoh", "f": 1 / (6 * nc * Ts), "amp": 2 * Ed / np.pi}
    if U is None:
        if Ed is None:
            raise ValueError(f"{scenario}: give the motor's voltage (V line-line rms)")
        U = np.sqrt(1.5) * 2 * Ed / np.pi
    amp = np.sqrt(2 / 3) * U
    if scenario == "dol":
        return {"u": lambda t: amp * np.exp(1j * w * np.asarray(t)), "hold": "linear", "f": f, "amp": amp,
                "Ed": None}
    Ed = Ed if Ed is not None else 1.05 * np.sqrt(2) * U
    mt = load_motulator()
    tm = (np.arange(n) + 0.5) * Ts
    u_abc = np.array(mt["complex2abc"](amp * np.exp(1j * w * tm)))  # (3, n)
    u_abc -= 0.5 * (u_abc.max(axis=0) + u_abc.min(axis=0))
    duty = np.round(PWM_LEVELS * np.clip(u_abc / Ed + 0.5, 0, 1)) / PWM_LEVELS
    return {"duty": duty.T, "Ed": Ed, "hold": "zoh", "f": f, "amp": amp}


# -- simulation ------------------------------------------------------------------------

class _Schedule:
    """A 'control system' for motulator's loop: replays precomputed duty ratios."""

    def __init__(self, Ts: float, duty: np.ndarray | None):
        self.Ts, self.duty, self.k = Ts, duty, 0

    def __call__(self, mdl):
        d = np.zeros(3) if self.duty is None else self.duty[min(self.k, len(self.duty) - 1)]
        self.k += 1
        return self.Ts, d

    def post_process(self):
        pass


def _source_classes(mt: dict):
    if "SineSource" not in _CACHE:
        base = mt["model"].VoltageSourceConverter

        class SineSource(base):
            """Ideal three-phase voltage source ``u(t)`` in place of a converter."""

            def __init__(self, fun):
                super().__init__(u_dc=0.0)
                self.fun = fun

            def set_outputs(self, t):
                self.out.u_cs, self.out.u_dc = self.fun(t), 0.0

            def post_process_states(self):
                self.data.u_dc = np.zeros(np.size(self.data.t))
                self.data.u_cs = self.fun(self.data.t)

        class OpenStator(mt["Subsystem"]):
            """The machine after its supply contactor opened: no current, no torque."""

            def set_outputs(self, _):
                self.out.i_ss, self.out.tau_M = 0j, 0.0

            def post_process_states(self):
                self.data.tau_M = np.zeros(np.size(self.data.t))
                self.data.i_ss = np.zeros(np.size(self.data.t), dtype=complex)

        _CACHE.update(SineSource=SineSource, OpenStator=OpenStator)
    return _CACHE["SineSource"], _CACHE["OpenStator"]


def _simulate(mt, converter, machine, mechanics, Ts: float, n: int, duty, pwm: bool):
    """Run motulator's simulation loop for ``n`` samples; returns the model after post-processing."""
    mdl = mt["model"].Drive(converter, machine, mechanics)
    mdl.delay = mt["Delay"](0)  # the schedule is the applied sequence: no computational delay
    if pwm:
        mdl.pwm = mt["CarrierComparison"](N=PWM_LEVELS)
    mt["model"].Simulation(mdl, _Schedule(Ts, duty)).simulate(t_stop=(n - 1.5) * Ts)
    return mdl


def _sample(tt: np.ndarray, t: np.ndarray, x: np.ndarray) -> np.ndarray:
    x = np.asarray(x)
    if np.iscomplexobj(x):
        return np.interp(tt, t, x.real) + 1j * np.interp(tt, t, x.imag)
    return np.interp(tt, t, x)


def _coast_time(par: dict, w0: float, cap: float) -> float:
    """Time (s) for the free rotor to coast from ``w0`` (mechanical rad/s) to rest, capped."""
    J, fv, fc = par["J"], par["fv"], par["fc"]
    if fv > 0 and fc > 0:
        t = J / fv * np.log1p(w0 * fv / fc)
    elif fc > 0:
        t = J * w0 / fc
    elif fv > 0:
        t = J / fv * np.log(100.0)
    else:
        t = cap
    return float(min(cap, 1.1 * t + 0.2))


# -- noise and output ------------------------------------------------------------------

def _noise(rng: np.random.Generator, noise: dict, Ts: float, rec: dict) -> dict:
    """White and coloured current noise, voltage noise, speed noise and quantisation."""
    n = len(rec["t"])
    out = dict(rec)
    a = np.exp(-2 * np.pi * float(noise.get("current_colored_bandwidth", 50.0)) * Ts)
    for ch in ("i_r", "i_s"):
        out[ch] = rec[ch] + float(noise.get("current_std", 0.0)) * rng.standard_normal(n)
        e = rng.standard_normal(n)
        col = np.empty(n)
        col[0] = e[0]
        for k in range(1, n):  # first-order (AR(1)) coloured noise, unit stationary variance
            col[k] = a * col[k - 1] + np.sqrt(1 - a * a) * e[k]
        out[ch] += float(noise.get("current_colored_std", 0.0)) * col
    for ch in ("v_r", "v_s", "v_t"):
        out[ch] = rec[ch] + float(noise.get("voltage_std", 0.0)) * rng.standard_normal(n)
    out["speed"] = _speed_noise(rng, noise, rec["speed"], Ts)
    return out


def _speed_noise(rng, noise: dict, speed: np.ndarray, dt: float) -> np.ndarray:
    """The speed sensor: its own noise (a tachogenerator's brushes and commutation; none by
    default) through an RC filter of ``speed_filter`` s (none by default; bilinear at the sampling
    ``dt``, settled at the first value) that colours it, ``speed_coloured_std`` rad/s as it leaves
    the filter at any sampling, then the acquisition's white noise ``speed_std`` and quantisation."""
    tau = float(noise.get("speed_filter", 0.0))
    coloured = float(noise.get("speed_coloured_std", 0.0))
    if tau > 0.0 and len(speed) > 1:
        from scipy import signal

        b, a = signal.bilinear([1.0], [tau, 1.0], fs=1.0 / dt)
        zi = signal.lfilter_zi(b, a)
        speed = signal.lfilter(b, a, speed, zi=zi * speed[0])[0]
        if coloured > 0.0:  # white at the sensor, of the std that leaves ``coloured`` behind the filter
            white = coloured / math.sqrt(0.5 * (1.0 + a[1])) * rng.standard_normal(len(speed))
            speed = speed + signal.lfilter(b, a, white, zi=zi * coloured * rng.standard_normal())[0]  # stationary
    elif coloured > 0.0:  # no filter: the sensor's noise is white
        speed = speed + coloured * rng.standard_normal(len(speed))
    y = speed + float(noise.get("speed_std", 0.0)) * rng.standard_normal(len(speed))
    q = float(noise.get("speed_quantum", 0.0))
    return np.round(y / q) * q if q > 0 else y


def _write_csv(path: Path, cols: dict) -> None:
    names = list(cols)
    data = np.column_stack([np.asarray(cols[c], dtype=float) for c in names])
    np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt="%.12g")


def _dump(path: Path, doc: dict) -> None:
    path.write_text(yaml.safe_dump(_plain(doc), sort_keys=False))


def _plain(x):
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return float(x)
    if isinstance(x, (np.integer, int)) and not isinstance(x, bool):
        return int(x)
    return x


# -- entry point -----------------------------------------------------------------------

def make_motulator_dataset(motor: dict, scenario: str, effects: dict | None, noise: dict | None, seed: int,
                           out: Path, duration: float, sample_rate: float, stop: bool,
                           stop_mode: str = "open", stop_sample_rate: float = 1000.0,
                           stop_max_duration: float = 60.0) -> dict:
    """Simulate a start-up (and optionally the free stop) with motulator; write a data folder.

    Parameters
    ----------
    motor : dict
        ``parameters`` (or top-level) ``Rs`` (ohm), ``Ls``, ``Le`` (H), ``Rr`` (ohm, project
        referral ``Lr = Ls``), ``J`` (kg m^2), ``fv`` (N m s), ``fc`` (N m); ``pole_pairs``;
        ``voltage`` (V line-line rms), ``frequency`` (Hz, default 50); optional
        ``dc_link_voltage`` (V), ``rated_torque`` (N m) or ``rated_power`` (W, for loads).
    scenario : {"dol", "six_step", "pwm"}
        Direct-on-line sine start, six-step inverter start, or sine-PWM inverter start.
    effects : dict or None
        ``{name: options}`` for ``main_saturation`` (``size``: extra magnetising current at
        rated flux, fraction; ``exponent``; held out: ``form: steel_gap`` with ``iron_ratio``),
        ``two_mass`` (``size``: load-side share of the inertia; ``resonance_hz``;
        ``damping_ratio``; friction acts on, and the speed is sensed on, the load side; held
        out: ``form: slip_clutch`` with ``slip_share``; retired: ``form: elastomer``
        with ``hardening``), ``load_torque`` (``form``: ``step``, an
        active torque from ``time`` s; ``constant``, a passive motion-opposing torque from the
        start; ``quadratic``, ``k*w**2`` reaching ``torque`` at synchronous speed; held out,
        ``battery_charger`` connected at ``time`` s with a cut-in speed ``cut_in_ratio`` times
        synchronous speed, ``torque`` its torque at synchronous speed; retired, ``eddy_brake``
        excited at ``time`` s, ``critical_speed_ratio`` (its critical speed over
        synchronous speed) and ``field_time_constant`` s, ``torque`` its steady torque at
        synchronous speed; ``dc_generator`` closed at ``time`` s with ``emf`` V at
        synchronous speed, ``armature_time_constant`` s and ``brush_drop`` V, ``torque`` its
        steady torque at synchronous speed; ``torque`` N m or ``size`` fraction of rated torque,
        default 0.5).
    noise : dict or None
        ``current_std`` (A, white), ``current_colored_std`` (A) with
        ``current_colored_bandwidth`` (Hz, first-order, default 50), ``voltage_std`` (V), ``speed_std``
        (rad/s) and ``speed_quantum`` (rad/s); drawn from ``numpy.random.default_rng(seed)``;
        ``speed_filter`` (s, default none): the speed sensor's RC filter, before the noise.
    seed : int
        Noise seed; the same inputs and seed give identical files.
    out : Path
        Folder to write ``meta.yaml``, ``startup.csv``, optional ``stop.csv``, ``truth.yaml``.
    duration : float
        Start-up record length (s).
    sample_rate : float
        Samples per second (Hz); also the inverter's update rate.
    stop : bool
        Also simulate and write the free stop after the supply is removed at ``duration``.
    stop_mode : {"open", "short"}
        ``open``: the supply contactor opens, currents are zero at once; ``short``: the
        stator is short-circuited (zero voltage vector) and the trapped flux brakes the rotor.
    stop_sample_rate, stop_max_duration : float
        Stop record rate (Hz) and length cap (s); the record ends when the rotor is at rest.

    Returns
    -------
    dict
        The truth document written to ``truth.yaml``.
    """
    if scenario not in SCENARIOS:
        raise ValueError(f"scenario must be one of {SCENARIOS}, got {scenario!r}")
    if stop_mode not in ("open", "short"):
        raise ValueError(f"stop_mode must be open or short, got {stop_mode!r}")
    if not (duration > 0 and sample_rate > 0):
        raise ValueError("duration and sample_rate must be positive")
    m = _motor(motor)
    mt = load_motulator()
    Ts = 1.0 / float(sample_rate)
    n = int(round(duration * sample_rate)) + 1
    exc = _excitation(m, scenario, Ts, n)
    eff_list = effect_specs(effects, m, exc, duration)
    eff = {e["name"]: e for e in eff_list}
    g = gamma_from_project(m["par"])
    L_s = g["L_s"]
    if "main_saturation" in eff:
        fm = eff["main_saturation"]["form"]
        if fm.get("form") == "steel_gap":
            L_s, curve = steel_gap_inductance(L_s, fm["rated_flux"], eff["main_saturation"]["size"], fm["iron_ratio"])
            fm["flux_density"] = float(fm["rated_flux"] * M800_50A[-1, 0] / curve.table[1][-1])
        else:
            L_u, psi_k, S = fm["L_unsaturated"], fm["knee_flux"], fm["exponent"]
            L_s = lambda psi: L_u / (1 + (np.asarray(psi) / psi_k) ** S)  # noqa: E731
    par = mt["ImPars"](n_p=m["p"], R_s=g["R_s"], R_r=g["R_r"], L_ell=g["L_ell"], L_s=L_s)
    SineSource, OpenStator = _source_classes(mt)
    conv = SineSource(exc["u"]) if scenario == "dol" else mt["model"].VoltageSourceConverter(u_dc=exc["Ed"])
    machine = mt["model"].InductionMachine(par)
    mech = mechanics(mt, m, eff, exc)
    _simulate(mt, conv, machine, mech, Ts, n, exc.get("duty"), pwm=scenario == "pwm")

    tt = np.arange(n) * Ts
    i_s = _sample(tt, machine.data.t, machine.data.i_ss)
    u = exc["u"](tt) if scenario == "dol" else mt["abc2complex"](exc["duty"].T) * exc["Ed"]
    w_key = "w_L" if "two_mass" in eff else "w_M"
    rec = {"t": tt, **dict(zip(("v_r", "v_s", "v_t"), mt["complex2abc"](u), strict=True)),
           **dict(zip(("i_r", "i_s"), mt["complex2abc"](i_s)[:2], strict=True)),
           "speed": _sample(tt, mech.data.t, getattr(mech.data, w_key))}
    rng = np.random.default_rng(seed)
    noise = dict(noise or {})
    rec = _noise(rng, noise, Ts, rec)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    _write_csv(out / "startup.csv", rec)

    stop_info = None
    if stop:
        Tq = 1.0 / float(stop_sample_rate)
        w0 = float(getattr(mech.data, w_key)[-1])
        coast = dict(m["par"])
        if "load_torque" in eff and eff["load_torque"]["form"]["form"] == "dc_generator":
            g = eff["load_torque"]["form"]["generator"]
            coast["fv"] += g["k_e"] ** 2 / g["R_a"]  # the generator brakes like a viscous torque
        if "load_torque" in eff and eff["load_torque"]["form"]["form"] == "eddy_brake":
            b = eff["load_torque"]["form"]["brake"]
            coast["fv"] += 2 * b["T_k"] / b["w_k"]  # the brake at low speed: its slope there, fully excited
        # a battery charger adds nothing: it stops braking below its cut-in speed (a longer, safe estimate)
        ns = int(round(_coast_time(coast, abs(w0), stop_max_duration) / Tq)) + 1
        mech_state = {k: getattr(mech.data, k)[-1] for k in vars(mech.sol_states)}
        mech2 = mechanics(mt, m, eff, exc, stop_at=duration)
        mech2.state.__dict__.update(mech_state)
        if stop_mode == "open":
            mach2, conv2, duty2 = OpenStator(), mt["model"].VoltageSourceConverter(u_dc=0.0), None
        else:
            mach2 = mt["model"].InductionMachine(par)
            mach2.state.psi_ss, mach2.state.psi_rs = machine.data.psi_ss[-1], machine.data.psi_rs[-1]
            conv2, duty2 = mt["model"].VoltageSourceConverter(u_dc=0.0), np.ones((ns, 3))
        _simulate(mt, conv2, mach2, mech2, Tq, ns, duty2, pwm=False)
        ts = np.arange(ns) * Tq
        speed = _speed_noise(rng, noise, _sample(ts, mech2.data.t, getattr(mech2.data, w_key)), Tq)
        _write_csv(out / "stop.csv", {"t": ts, "speed": speed})
        stop_info = {"mode": stop_mode, "sample_time": Tq, "duration": float(ts[-1]), "initial_speed": w0}

    meta = {"kind": "startup", "pole_pairs": m["p"], "sample_time": Ts, "input_hold": exc["hold"],
            "supply_frequency": float(exc["f"])}
    if exc["Ed"] is not None:
        meta["dc_link_voltage"] = float(exc["Ed"])
    meta["description"] = (f"motulator {mt['version']} simulation of {m['name']}: {scenario} start"
                           + (f" with {', '.join(eff)}" if eff else "") + (", free stop" if stop else ""))
    _dump(out / "meta.yaml", meta)
    truth = {"source": "motulator", "motulator_version": mt["version"], "scenario": scenario,
             "parameters": m["par"], "pole_pairs": m["p"],
             "parametrisation": "project referral Lr = Ls; Le = Ls - Lm^2/Lr; Rr = Lr/tau_r",
             "gamma_model": {**g, "L_s": m["par"]["Ls"], "note": "L_s at rated flux when main_saturation is on"},
             "effects": eff_list, "noise": noise, "seed": int(seed),
             "supply": {"amplitude": float(exc["amp"]), "frequency": float(exc["f"]),
                        "dc_link_voltage": exc["Ed"],
                        "switching_frequency": 0.5 * sample_rate if scenario == "pwm" else None},
             "coulomb_smoothing_speed": COULOMB_SMOOTHING, "stop": stop_info}
    _dump(out / "truth.yaml", truth)
    return _plain(truth)

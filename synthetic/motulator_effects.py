"""The motulator source's effects (:mod:`synthetic.motulator_source`): their options, and
motulator's mechanics built for them, with the held-out forms.

The motulator source injects three effects, each with motulator's own model as its
development form: ``main_saturation`` (motulator's saturable Gamma model,
``L_s(psi) = L_u/(1 + (psi/psi_k)**S)``), ``two_mass`` (motulator's linear two-mass shaft) and
``load_torque`` (a step, constant or quadratic torque through motulator's ``tau_L(t)`` and
``B_L(w)``). The split of forms is kept with the independent plant's, in
:mod:`synthetic.independent.forms` (``MOTULATOR_DEVELOPMENT``, ``MOTULATOR_HELDOUT``). The
held-out forms, written here on motulator's own classes:

``steel_gap`` (main_saturation)
    The no-load curve of an air gap in series with an iron path of the measured steel
    M800-50A (:data:`M800_50A`; the construction of
    :meth:`synthetic.independent.curves.MagnetisingCurve.steel_gap`, another steel than the
    plant's), given to motulator as ``L_s(psi) = psi / i(psi)``, with the iron path
    ``iron_ratio`` times the gap: the size convention of motulator's form (``L_s(psi_n) = Ls``,
    the largest ``L_s`` is ``(1 + size) Ls``; M800-50A's permeability rises from low fields,
    so ``L_s`` at zero flux is somewhat lower).
``elastomer`` (two_mass)
    motulator's two-mass shaft with a progressive elastomer coupling,
    ``tau_S = K_S (z + z^3/(3 z_r^2)) + C_S sqrt(1 + (z/z_r)^2) (w_M - w_L)``, the incremental
    stiffness ``hardening`` times harder at the rated torque's twist (as the plant's
    ``elastomer`` form). Retired from the held-out forms: the diagnosis's coupling has this
    hardening since (drawn by name and in ``all`` only).
``slip_clutch`` (two_mass)
    motulator's two-mass shaft with a friction torque limiter (slip hub) in series with the
    spring (as the plant's ``slip_clutch`` form): ``tau_S = clip(K_S z, +-T_lim) + C_S (w_M - w_L)``,
    the twist held while the hub slips (the spring at the limit, the halves moving apart);
    ``T_lim`` a share ``slip_share`` of the rated torque.
``dc_generator`` (load_torque)
    A separately excited DC generator on the shaft (the load side of a two-mass shaft): an
    extra state, the armature current, ``L_a di_a/dt = k_e w - R_a i_a - U_b tanh(i_a/i_b)``
    from the instant ``time`` on (zero before), torque ``k_e i_a``; ``k_e`` from the EMF at
    synchronous speed, ``R_a`` so that the steady torque there is the drawn load torque.
    Retired from the held-out forms: the diagnosis's DC machine has the armature's lag since.
``eddy_brake`` (load_torque)
    An eddy-current brake on the shaft (the load side of a two-mass shaft), excited from the
    instant ``time`` on: ``T = T_k (1 - exp(-(t - time)/tau_f))^2 2 (w/w_k)/(1 + (w/w_k)^2)``,
    the brake's torque-speed law with its critical speed ``w_k`` (Wouterse, IEE Proc. B
    138(4), 1991) times the square of the excitation current rising with the field's time
    constant ``tau_f``; ``T_k`` so that the steady torque at synchronous speed is the drawn
    load torque (as the independent plant's ``eddy_brake``). Retired from the held-out forms:
    the diagnosis's load has the brake's law since.
``battery_charger`` (load_torque)
    A permanent-magnet generator on the shaft (the load side of a two-mass shaft) charging a
    battery through a diode bridge, connected at ``time``: no current below the cut-in speed
    ``w_c`` (the battery's voltage plus the diodes' drop), then ``T = T_L (|w| - w_c)/(w_sync - w_c)``
    (as the independent plant's ``battery_charger``); ``w_c`` a share ``cut_in_ratio`` of
    synchronous speed, ``T_L`` the drawn load torque.

There are no held-out forms for the effects motulator does not inject (every other effect
of the catalogue): the motulator source only offers these three.
"""

from __future__ import annotations

import numpy as np

from synthetic.independent.curves import MagnetisingCurve
from synthetic.independent.forms import MOTULATOR_HELDOUT, motulator_forms_of

EFFECTS = ("main_saturation", "two_mass", "load_torque")
#: Speed (mechanical rad/s) below which Coulomb friction is linear (viscous) in the plant.
COULOMB_SMOOTHING = 1e-3

#: Magnetisation curve of the non-oriented electrical steel M800-50A (0.5 mm laminations):
#: ``B`` (T) against ``H`` (A/m), amplitudes at 50 Hz, as tabulated in the pyleecan material
#: library (Eomys, Apache-2.0, ``Data/Material/M800-50A.json``), with ``(0, 0)`` prepended.
M800_50A = np.array([[0.0, 0.0], [0.1, 84.0], [0.2, 107.0], [0.3, 121.0], [0.4, 133.0], [0.5, 145.0],
                     [0.6, 156.0], [0.7, 168.0], [0.8, 180.0], [0.9, 194.0], [1.0, 209.0], [1.1, 228.0],
                     [1.2, 254.0], [1.3, 304.0], [1.4, 402.0], [1.5, 660.0], [1.6, 1480.0], [1.7, 3710.0],
                     [1.8, 7300.0]])


def steel_gap_inductance(L_s: float, psi_n: float, size: float, iron_ratio: float):
    """``(L_s(psi), curve)``: motulator's stator inductance (H) as a function of the stator
    flux magnitude (Wb) for the ``steel_gap`` form (see module docstring), and the
    :class:`~synthetic.independent.curves.MagnetisingCurve` it is read from."""
    curve = MagnetisingCurve.steel_gap(L_s * (1 + size), psi_n, size / (1 + size), iron_ratio, M800_50A)
    i_tab, psi_tab = (np.asarray(v) for v in curve.table)

    def inductance(psi):
        psi = np.abs(np.asarray(psi, float))
        i = np.where(psi <= psi_tab[-1], np.interp(psi, psi_tab, i_tab), i_tab[-1] + (psi - psi_tab[-1]) / curve.Linf)
        return np.where(psi > 0, psi / np.where(psi > 0, i, 1.0), curve.Lm0)

    return inductance, curve


def elastomer_class(base):
    """motulator's two-mass class ``base`` with the ``elastomer`` coupling (``par.z_r`` rad)."""

    class ElastomerTwoMass(base):
        def __init__(self, par, z_r: float, tau_L=lambda t: 0 * t):
            super().__init__(par, tau_L=tau_L)
            self.z_r = z_r

        def set_outputs(self, t):
            super().set_outputs(t)
            out = self.out
            q = np.real(out.theta_ML) / self.z_r
            out.tau_S = (self.par.K_S * np.real(out.theta_ML) * (1 + q * q / 3)
                         + self.par.C_S * np.sqrt(1 + q * q) * (out.w_M - out.w_L))

    return ElastomerTwoMass


def slip_clutch_class(base):
    """motulator's two-mass class ``base`` with a ``slip_clutch`` (a torque limiter slipping at
    ``T_lim`` N m in series with the spring)."""

    class SlipClutchTwoMass(base):
        def __init__(self, par, T_lim: float, tau_L=lambda t: 0 * t):
            super().__init__(par, tau_L=tau_L)
            self.T_lim = T_lim

        def set_outputs(self, t):
            super().set_outputs(t)
            out = self.out
            spring = np.clip(self.par.K_S * np.real(out.theta_ML), -self.T_lim, self.T_lim)
            out.tau_S = spring + self.par.C_S * (out.w_M - out.w_L)

        def rhs(self):
            d = super().rhs()
            tk, dw = self.par.K_S * np.real(self.state.theta_ML), np.real(self.state.w_M - self.state.w_L)
            if (tk >= self.T_lim and dw > 0) or (tk <= -self.T_lim and dw < 0):
                d[3] = 0.0  # the hub slips: the spring keeps its twist
            return d

    return SlipClutchTwoMass


def elastomer_twist(K_S: float, rated_torque: float, hardening: float) -> float:
    """The hardening twist ``z_r`` (rad) of an elastomer coupling of small-twist stiffness
    ``K_S`` (N m/rad) that is ``hardening`` times stiffer at ``rated_torque`` (N m)."""
    return rated_torque / (K_S * (1 + (hardening - 1) / 3)) / np.sqrt(hardening - 1)


def generator_class(base):
    """motulator's mechanics class ``base`` with a DC generator load (extra state ``i_a``)."""

    class GeneratorLoaded(base):
        def __init__(self, *args, generator: dict, **kw):
            super().__init__(*args, **kw)
            self.gen = generator
            self.state.i_a = 0.0
            self.sol_states.i_a = []
            self._t = 0.0

        def _speed(self):
            return np.real(self.out.w_L if hasattr(self.out, "w_L") else self.out.w_M)

        def set_outputs(self, t):
            super().set_outputs(t)
            self._t = t
            self.out.tau_L_tot = self.out.tau_L_tot + self.gen["k_e"] * np.real(self.state.i_a)

        def rhs(self):
            g, ia = self.gen, np.real(self.state.i_a)
            if self._t < g["time"]:
                d_ia = 0.0
            else:
                d_ia = (g["k_e"] * self._speed() - g["R_a"] * ia - g["U_b"] * np.tanh(ia / g["i_b"])) / g["L_a"]
            return super().rhs() + [d_ia]

    return GeneratorLoaded


def generator(torque: float, w_sync: float, emf: float, time_constant: float, brush_drop: float,
              time: float) -> dict:
    """The DC generator of a drawn ``dc_generator`` load: ``torque`` (N m) at ``w_sync``
    (mechanical rad/s) with the EMF ``emf`` (V) there, armature time constant (s), brush
    drop (V), armature closed at ``time`` (s)."""
    k_e = emf / w_sync
    R_a = k_e**2 * w_sync / torque
    return {"k_e": k_e, "R_a": R_a, "L_a": time_constant * R_a, "U_b": brush_drop, "i_b": 0.01 * torque / k_e,
            "time": time}


def shaft_load_class(base, torque):
    """motulator's mechanics class ``base`` with a passive load on the load side whose torque
    ``torque(load, t, w)`` (N m, at time ``t`` s and load-side speed ``w`` rad/s) comes from
    the load's parameters ``load`` (the ``shaft_load`` argument)."""

    class ShaftLoaded(base):
        def __init__(self, *args, shaft_load: dict, **kw):
            super().__init__(*args, **kw)
            self.shaft_load = shaft_load

        def set_outputs(self, t):
            super().set_outputs(t)
            w = np.real(self.out.w_L if hasattr(self.out, "w_L") else self.out.w_M)
            self.out.tau_L_tot = self.out.tau_L_tot + torque(self.shaft_load, t, w)

    return ShaftLoaded


def brake_torque(b: dict, t: float, w: float) -> float:
    """The eddy-current brake :func:`brake` ``b``'s torque (N m) at ``t`` (s) and speed ``w`` (rad/s)."""
    field = 1.0 - np.exp(-(t - b["time"]) / b["tau_f"]) if t >= b["time"] else 0.0
    q = w / b["w_k"]
    return b["T_k"] * field * field * 2 * q / (1 + q * q)


def charger_torque(c: dict, t: float, w: float) -> float:
    """The battery charger :func:`charger` ``c``'s torque (N m) at ``t`` (s) and speed ``w`` (rad/s)."""
    over = max(abs(w) - c["w_c"], 0.0) if t >= c["time"] else 0.0
    return np.sign(w) * c["T_L"] * over / (c["w_sync"] - c["w_c"])


def brake(torque: float, w_sync: float, critical_speed_ratio: float, field_time_constant: float,
          time: float) -> dict:
    """The eddy-current brake of a drawn ``eddy_brake`` load: ``torque`` (N m) at ``w_sync``
    (mechanical rad/s), critical speed ``critical_speed_ratio`` times ``w_sync``, field time
    constant (s), excited from ``time`` (s)."""
    w_k = critical_speed_ratio * w_sync
    q = w_sync / w_k
    return {"T_k": torque * (1 + q * q) / (2 * q), "w_k": w_k, "tau_f": field_time_constant, "time": time}


def charger(torque: float, w_sync: float, cut_in_ratio: float, time: float) -> dict:
    """The battery charger of a drawn ``battery_charger`` load: ``torque`` (N m) at ``w_sync``
    (mechanical rad/s), cut-in speed ``cut_in_ratio`` times ``w_sync``, connected at ``time`` (s)."""
    if not 0.0 <= cut_in_ratio < 1.0:
        raise ValueError(f"load_torque: cut_in_ratio must be in [0, 1), got {cut_in_ratio}")
    return {"T_L": torque, "w_c": cut_in_ratio * w_sync, "w_sync": w_sync, "time": time}


def effect_specs(effects: dict | None, m: dict, exc: dict, duration: float) -> list[dict]:
    """Validate the requested effects and fill in their defaults (sizes and forms)."""
    out = []
    for name, opts in dict(effects or {}).items():
        opts = dict(opts or {})
        if name not in EFFECTS:
            raise ValueError(f"effect {name!r} is not available from the motulator source (it offers "
                             f"{', '.join(EFFECTS)}); use the project's independent plant for the others")
        kind = opts.get("form")
        if kind is not None and kind not in motulator_forms_of(name, "all"):
            raise ValueError(f"{name}: form must be one of {motulator_forms_of(name, 'all')}, got {kind!r}")
        held = {"form_set": "heldout"} if kind in MOTULATOR_HELDOUT[name] else {}
        if name == "main_saturation":
            size, S = float(opts.get("size", np.sqrt(0.1 * 0.6))), float(opts.get("exponent", 7.0))
            psi_n = exc["amp"] / (2 * np.pi * exc["f"])
            form = {"exponent": S, "rated_flux": psi_n, "L_unsaturated": m["par"]["Ls"] * (1 + size),
                    "knee_flux": psi_n * size ** (-1 / S) if size > 0 else float("inf")}
            if kind == "steel_gap":
                form = {"form": kind, "rated_flux": psi_n, "L_unsaturated": m["par"]["Ls"] * (1 + size),
                        "iron_ratio": float(opts.get("iron_ratio", 250.0))}
            out.append({"name": name, "size": size, "size_name": "extra magnetising current at rated flux",
                        "unit": "fraction", "form": form, **held})
        elif name == "two_mass":
            size = float(opts.get("size", 0.5))
            if not 0 < size < 1:
                raise ValueError(f"two_mass: size (load share of the inertia) must be in (0, 1), got {size}")
            f_r, zeta = float(opts.get("resonance_hz", 30.0)), float(opts.get("damping_ratio", 0.05))
            J = m["par"]["J"]
            J_L, J_eq = size * J, size * (1 - size) * J  # J_eq = J_M J_L / (J_M + J_L)
            K_S = (2 * np.pi * f_r) ** 2 * J_eq
            form = {"resonance_hz": f_r, "damping_ratio": zeta, "J_M": J - J_L, "J_L": J_L, "K_S": K_S,
                    "C_S": 2 * zeta * np.sqrt(K_S * J_eq)}
            if kind == "elastomer":
                if m["rated_torque"] is None:
                    raise ValueError("two_mass: the elastomer form needs the motor's rated_torque or rated_power")
                form.update(form=kind, hardening=float(opts.get("hardening", 2.0)),
                            z_r=elastomer_twist(K_S, m["rated_torque"], float(opts.get("hardening", 2.0))))
            if kind == "slip_clutch":
                if m["rated_torque"] is None:
                    raise ValueError("two_mass: the slip_clutch form needs the motor's rated_torque or rated_power")
                share = float(opts.get("slip_share", 1.0))
                form.update(form=kind, slip_share=share, T_lim=share * m["rated_torque"])
            out.append({"name": name, "size": size, "size_name": "load-side share of the inertia",
                        "unit": "fraction", "form": form, **held})
        else:
            kind = kind or "step"
            torque = opts.get("torque")
            if torque is None:
                if m["rated_torque"] is None:
                    raise ValueError("load_torque: give torque (N m), or the motor's rated_torque or rated_power")
                torque = float(opts.get("size", 0.5)) * m["rated_torque"]
            form = {"form": kind, "torque": float(torque), "time": float(opts.get("time", 0.6 * duration))}
            w_sync = 2 * np.pi * exc["f"] / m["p"]
            if kind == "dc_generator":
                form["generator"] = generator(float(torque), w_sync, float(opts.get("emf", 200.0)),
                                              float(opts.get("armature_time_constant", 0.01)),
                                              float(opts.get("brush_drop", 1.5)), form["time"])
            if kind == "eddy_brake":
                form["brake"] = brake(float(torque), w_sync, float(opts.get("critical_speed_ratio", 0.6)),
                                      float(opts.get("field_time_constant", 0.05)), form["time"])
            if kind == "battery_charger":
                form["charger"] = charger(float(torque), w_sync, float(opts.get("cut_in_ratio", 0.5)), form["time"])
            size_name = ("steady generator torque at synchronous speed" if kind == "dc_generator"
                         else "steady brake torque at synchronous speed" if kind == "eddy_brake"
                         else "charging torque at synchronous speed" if kind == "battery_charger"
                         else "load torque (at synchronous speed for quadratic)")
            out.append({"name": name, "size": float(torque), "size_name": size_name, "unit": "N m", "form": form,
                        **held})
    return out


def mechanics(mt: dict, m: dict, eff: dict, exc: dict, stop_at: float | None = None):
    """motulator mechanics with friction, load torque and the two-mass shaft as requested.

    ``stop_at`` (s): build the mechanics of the free stop that follows a start-up of that
    length; a load already applied then stays on as a passive (motion-opposing) torque."""
    par = m["par"]
    fv, fc, eps = par["fv"], par["fc"], COULOMB_SMOOTHING
    load, k_quad, fc_load = eff.get("load_torque"), 0.0, 0.0
    tau_L = lambda t: 0 * np.asarray(t)  # noqa: E731
    gen = brk = chg = None
    if load is not None and load["form"]["form"] == "dc_generator":
        gen = dict(load["form"]["generator"])
        if stop_at is not None:  # the stop's clock starts at zero: a generator switched on stays on
            gen["time"] = 0.0 if gen["time"] <= stop_at else gen["time"] - stop_at
        load = None
    if load is not None and load["form"]["form"] == "eddy_brake":
        brk = dict(load["form"]["brake"])
        if stop_at is not None:  # the stop's clock starts at zero: the excitation goes on rising
            brk["time"] -= stop_at
        load = None
    if load is not None and load["form"]["form"] == "battery_charger":
        chg = dict(load["form"]["charger"])
        if stop_at is not None:  # the stop's clock starts at zero: a charger connected stays connected
            chg["time"] = 0.0 if chg["time"] <= stop_at else chg["time"] - stop_at
        load = None
    if load is not None:
        T, t0 = load["form"]["torque"], load["form"]["time"]
        if load["form"]["form"] == "quadratic":
            k_quad = T / (2 * np.pi * exc["f"] / m["p"]) ** 2
        elif load["form"]["form"] == "constant" or (stop_at is not None and t0 <= stop_at):
            fc_load = T  # a passive load: opposes the motion, like Coulomb friction
        elif stop_at is None:
            tau_L = lambda t: T * (np.asarray(t) >= t0)  # noqa: E731

    def B_L(a):
        return fv + (fc + fc_load) / np.maximum(a, eps) + k_quad * a

    tm = eff.get("two_mass")
    shaft = (brk, brake_torque) if brk is not None else (chg, charger_torque) if chg is not None else None
    extra = {"generator": gen} if gen is not None else {"shaft_load": shaft[0]} if shaft is not None else {}

    def loaded(cls):
        if gen is not None:
            return generator_class(cls)
        return shaft_load_class(cls, shaft[1]) if shaft is not None else cls

    if tm is None:
        return loaded(mt["model"].StiffMechanicalSystem)(J=par["J"], B_L=B_L, tau_L=tau_L, **extra)
    fm = tm["form"]
    pars = mt["TwoMassPars"](J_M=fm["J_M"], J_L=fm["J_L"], K_S=fm["K_S"], C_S=fm["C_S"], B_L=B_L)
    cls, args = mt["model"].TwoMassMechanicalSystem, (pars,)
    if fm.get("form") == "elastomer":
        cls, args = elastomer_class(cls), (pars, fm["z_r"])
    if fm.get("form") == "slip_clutch":
        cls, args = slip_clutch_class(cls), (pars, fm["T_lim"])
    return loaded(cls)(*args, tau_L=tau_L, **extra)

"""Search bounds of the time-domain problem: the user's (``bounds=``), the motor preset's, or
derived from the data; checked once (two finite numbers, low < high, the parameter's physical
sign), with errors naming the config key."""

from __future__ import annotations

import math

import numpy as np

from benchmark.core.errors import ConfigError, DataError
from benchmark.problems.timedomain.data import StartupDataset
from benchmark.problems.timedomain.frames import fundamental, phasor_speed
from benchmark.problems.timedomain.load_checks import input_power
from benchmark.problems.timedomain.motor import PARAMETER_NAMES
from benchmark.problems.timedomain.settings import WEIGHT_KEYS, TimeDomainSettings


# -- bounds --------------------------------------------------------------------------
def derive_bounds(ds: StartupDataset, names: tuple[str, ...]) -> dict[str, tuple[float, float]]:
    """Search bounds from the data alone, for a motor with no preset.

    From the last fifth of the first start-up (near no-load steady state) the fundamental
    voltage ``V1`` and current ``I0`` give the no-load reactance ``V1/I0 ~ w_e Ls``; the peak
    start-up current ``I_pk`` gives the short-circuit impedance ``Z_sc = V1/I_pk ~
    |Rs + Rr' + j w_e Le|``. The energy delivered during the start-up bounds the inertia
    (``J <= 2 E_in / w_M^2``), and the input power at the end bounds the friction.
    Each range spans well over a decade around these rough values, so that motors from
    0.5 kW to 200 kW identify without hand-set bounds. Returns ``{name: (low, high)}``.
    """
    r = ds.startups[0]
    n = len(r.t)
    tail = slice(int(0.8 * n), n)
    v = r.v_alpha + 1j * r.v_beta
    i = r.i_alpha + 1j * r.i_beta
    t = r.t
    # electrical supply frequency from the voltage phasor's rotation over the tail
    w_e = abs(phasor_speed(r.v_alpha[tail], r.v_beta[tail], t[tail]))
    if not w_e > 0:
        raise ConfigError("bounds: cannot derive bounds: the start-up voltage does not rotate; give bounds=...")
    V1 = abs(fundamental(v[tail], t[tail], w_e))
    I0 = abs(fundamental(i[tail], t[tail], w_e))
    I_pk = float(np.max(np.abs(i)))
    Ls0 = V1 / (I0 * w_e)
    Z_sc = V1 / I_pk
    Le0 = Z_sc / w_e
    w_end = float(np.mean(r.speed[tail])) if np.all(np.isfinite(r.speed[tail])) else math.nan
    if not w_end > 0:  # no speed sensor: near no load the rotor runs close to synchronous speed
        w_end = w_e / ds.pole_pairs
    power = input_power(r)
    E_in = float(np.sum(power) * ds.sample_time)
    if "J" in names and not E_in > 0:
        raise DataError(r.source, f"the start-up takes in no energy ({E_in:.3g} J from 1.5 (v_alpha i_alpha + v_beta "
                                  "i_beta)), which a motor accelerating from rest must: do the voltages and currents "
                                  "belong together as wired (line-to-line voltages under the phase columns, a probe "
                                  "reversed, current columns of other phases)? See the warnings above; give "
                                  "++bounds.J=[low,high] to go on regardless")
    J_max = 2.0 * E_in / max(w_end, 1e-9) ** 2
    # friction and windage loss <= no-load input power <= no-load apparent power S0; the mean
    # power of a zoh (inverter) record can come out near zero, so S0 / 4 is a floor
    S0 = 1.5 * V1 * I0
    P_end = max(float(np.mean(power[tail])), 0.25 * S0, 1e-9)
    bounds = {
        "Rs": (Z_sc / 100.0, 2.0 * Z_sc),
        "Rr": (Z_sc / 100.0, 2.0 * Z_sc),
        "Ls": (Ls0 / 3.0, 3.0 * Ls0),
        # the peak start-up current includes the DC offset (up to twice the AC peak): Le0 can be
        # low by a factor of two
        "Le": (Le0 / 20.0, 4.0 * Le0),
        "J": (J_max / 50.0, J_max),
        "fv": (0.0, P_end / w_end**2),
        "fc": (0.0, P_end / w_end),
    }
    return {k: bounds[k] for k in names}


#: Sign each parameter's bounds must respect: > 0 ("positive") or >= 0 ("non-negative").
PARAMETER_SIGNS = {"Rs": "positive", "Ls": "positive", "Le": "positive", "Rr": "positive", "J": "positive",
                   "fv": "non-negative", "fc": "non-negative"}


def check_config(run) -> None:
    """Configuration checks of this problem that need no data, run by the harness before any
    work starts (``run``: the resolved run configuration): ``bounds`` names and values,
    ``problem.cost``, ``problem.friction_case``, ``problem.stator_resistance``,
    ``problem.held_friction``."""
    user = run.get("bounds")
    if user is not None:
        if not hasattr(user, "items"):
            raise ConfigError(f"bounds: expected a mapping {{name: [low, high]}}, got {user!r}")
        unknown = sorted(str(k) for k in user if k not in PARAMETER_NAMES)
        if unknown:
            raise ConfigError(f"bounds: unknown parameter(s) {unknown}; valid: {list(PARAMETER_NAMES)}")
        for n, val in user.items():
            _check_pair(f"bounds.{n}", n, val)
    pcfg = run.get("problem") or {}
    cost = pcfg.get("cost") or {}
    exponent = cost.get("exponent", 1)
    if isinstance(exponent, bool) or exponent not in (1, 2):
        raise ConfigError(f"problem.cost.exponent: must be 1 (eq. 15) or 2 (eq. 14), got {exponent!r}")
    weights = cost.get("weights") or {}
    if not hasattr(weights, "items"):
        raise ConfigError(f"problem.cost.weights: expected a mapping {{channel: weight}}, got {weights!r}")
    for k, w in weights.items():
        if k not in WEIGHT_KEYS:
            raise ConfigError(f"problem.cost.weights.{k}: unknown channel; valid: {list(WEIGHT_KEYS)}")
        if isinstance(w, bool) or not isinstance(w, (int, float)) or not math.isfinite(w) or w < 0:
            raise ConfigError(f"problem.cost.weights.{k}: must be a non-negative number, got {w!r}")
    case = pcfg.get("friction_case", 2)
    if isinstance(case, bool) or case not in (1, 2):
        raise ConfigError(f"problem.friction_case: must be 1 (no Coulomb friction) or 2 (with), got {case!r}")
    rs = pcfg.get("stator_resistance", "auto")
    if rs not in ("free", "prior", "fixed", "auto"):
        raise ConfigError(f"problem.stator_resistance: must be free, prior, fixed or auto, got {rs!r}")
    spread = pcfg.get("stator_prior_spread", 20.0)
    if isinstance(spread, bool) or not isinstance(spread, (int, float)) or not math.isfinite(spread) or spread <= 0:
        raise ConfigError(f"problem.stator_prior_spread: must be a positive number of kelvin, got {spread!r}")
    held = pcfg.get("held_friction")
    if held is not None:
        if not hasattr(held, "items") or sorted(str(k) for k in held) != ["fc", "fv"]:
            raise ConfigError(f"problem.held_friction: expected {{fv: N m s/rad, fc: N m}} or null, got {held!r}")
        for k, v in held.items():
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                raise ConfigError(f"problem.held_friction.{k}: must be a non-negative number, got {v!r}")


def _check_pair(src: str, name: str, val) -> tuple[float, float]:
    """``[low, high]`` -> floats, or a ConfigError naming ``src``: two finite numbers, low <
    high, and the parameter's physical sign."""
    if isinstance(val, (str, bytes)) or not hasattr(val, "__len__") or len(val) != 2:
        raise ConfigError(f"{src}: expected [low, high], got {val!r}")
    if any(isinstance(v, bool) for v in val):
        raise ConfigError(f"{src}: expected two numbers [low, high], got {list(val)!r}")
    try:
        lo, hi = (float(v) for v in val)
    except (TypeError, ValueError, OverflowError):
        raise ConfigError(f"{src}: expected two numbers [low, high], got {list(val)!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ConfigError(f"{src}: bounds must be finite numbers, got [{lo}, {hi}]")
    if lo >= hi:
        raise ConfigError(f"{src}: low {lo} >= high {hi} (did you swap low and high?)")
    sign = PARAMETER_SIGNS.get(name)
    if sign == "positive" and lo <= 0:
        raise ConfigError(f"{src}: {name} must be positive; low bound {lo} is not physical")
    if sign == "non-negative" and lo < 0:
        raise ConfigError(f"{src}: {name} cannot be negative; low bound {lo} is not physical")
    return lo, hi


def choose_bounds(settings: TimeDomainSettings, names, ds) -> dict:
    user, preset_bounds = settings.bounds, settings.preset_bounds
    if user is not None:
        unknown = set(user) - set(names)
        if unknown:
            raise ConfigError(f"bounds: unknown parameter(s) {sorted(unknown)}; searched here: {names}"
                              + _not_searched_hint(unknown, names))
    out = {}
    derived = None
    given = set(user or ()) | set(preset_bounds or ())
    for n in names:
        if user is not None and n in user:
            src, val = f"bounds.{n}", user[n]
        elif preset_bounds is not None and n in preset_bounds:
            src, val = f"motor.bounds.{n}", preset_bounds[n]
        else:
            if derived is None:  # the ones not given (a bound the data cannot give may be given)
                derived = _derive_or_explain(ds, tuple(m for m in names if m not in given))
            src, val = f"bounds.{n} (derived from data: give ++bounds.{n}=[low,high] to override)", derived[n]
        out[n] = _check_pair(src, n, val)
    return out


def _not_searched_hint(unknown, names) -> str:
    fixed = sorted(set(unknown) & set(PARAMETER_NAMES))
    if not fixed:
        return ""
    return (f" ({fixed} not searched: fv and fc follow from the stop record, J from a known inertia)")


def _derive_or_explain(ds, names) -> dict:
    """:func:`derive_bounds`, with a failure turned into a ConfigError that says what to give."""
    try:
        with np.errstate(all="ignore"):
            derived = derive_bounds(ds, names)
    except ConfigError:
        raise
    except (ValueError, FloatingPointError, ZeroDivisionError, np.linalg.LinAlgError, IndexError) as exc:
        raise ConfigError(f"bounds: cannot derive bounds from the data ({type(exc).__name__}: {exc}); "
                          f"give bounds for {list(names)}, e.g. bounds={{Rs:[0.1,10]}}") from None
    return derived

"""The unmodelled-effect catalogue (MODEL.md section 6).

Each effect exists twice: in the synthetic plant that makes "real" data (:meth:`Effect.plant`,
with a size in a documented realistic range and optional variations of its form), and as an
augmentation of the identification model with its own extra parameters
(:meth:`Effect.augment`). Both act on rows of the extended model
(:mod:`benchmark.problems.timedomain.extended`).

A new effect is one class (a subclass of :class:`Effect`) plus one YAML in ``conf/effect/``
naming it with ``_target_``; :func:`load_effects` builds them all.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from benchmark.core.errors import ConfigError

CONF_EFFECTS = Path(__file__).resolve().parents[2] / "conf" / "effect"


@dataclass(frozen=True)
class EffectContext:
    """Reference scales of a data set, computed from the data and the base fit.

    Attributes: w_e (supply angular frequency, rad/s), V1 (fundamental voltage amplitude, V),
    I_peak (peak start-up current, A), w_sync (synchronous mechanical speed, rad/s),
    dc_link_voltage (V, or the six-step equivalent pi V1 / 2), E_cu (copper-loss energy of the
    start-up, J), L_M (magnetising inductance of the base model, H), L_sigma (leakage, H).
    """

    w_e: float
    V1: float
    I_peak: float
    w_sync: float
    dc_link_voltage: float
    E_cu: float
    L_M: float
    L_sigma: float

    @property
    def flux(self) -> float:
        """Rated magnetising flux V1 / w_e, Wb."""
        return self.V1 / self.w_e


class Effect:
    """Base class. Subclasses set the class attributes and the three methods.

    Attributes
    ----------
    name : interface name (MODEL.md section 6).
    problem : ``timedomain`` or ``admittance``.
    size_name, size_unit : the size parameter of the plant and its unit.
    realistic : documented realistic range of the size.
    extra_names : the augmentation's extra parameters.
    physics, shows_in : one line each, for reports.
    """

    name = "effect"
    problem = "timedomain"
    size_name = "size"
    size_unit = "-"
    realistic: tuple[float, float] = (0.0, 1.0)
    extra_names: tuple[str, ...] = ()
    physics = ""
    shows_in = ""

    def __init__(self, realistic=None, **form):
        if realistic is not None:
            lo, hi = (float(v) for v in realistic)
            if not lo < hi:
                raise ConfigError(f"effect.{self.name}.realistic: low {lo} >= high {hi}")
            self.realistic = (lo, hi)
        self.form = dict(form)

    # plant
    def plant(self, row: np.ndarray, size: float, ctx: EffectContext, form: dict | None = None) -> np.ndarray:
        """A copy of the extended row with the effect injected at ``size``."""
        raise NotImplementedError

    # augmentation
    def extra_bounds(self, ctx: EffectContext) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError

    def extra_starts(self, ctx: EffectContext) -> list[np.ndarray]:
        """Starting values of the extra parameters for the local fits."""
        lo, hi = self.extra_bounds(ctx)
        return [lo + 0.25 * (hi - lo)]

    def augment(self, rows: np.ndarray, extras: np.ndarray, ctx: EffectContext) -> np.ndarray:
        """Rows (n, N_EXT) of the augmented model for extra-parameter rows (n, k)."""
        raise NotImplementedError

    def describe(self) -> dict:
        return {"name": self.name, "size": self.size_name, "unit": self.size_unit,
                "realistic": list(self.realistic), "extra_parameters": list(self.extra_names),
                "physics": self.physics, "shows_in": self.shows_in}


def load_effects(problem: str = "timedomain", names=None) -> dict[str, Effect]:
    """Every effect of ``problem`` declared in ``conf/effect/*.yaml`` (or only ``names``)."""
    from hydra.utils import instantiate

    out = {}
    for path in sorted(CONF_EFFECTS.glob("*.yaml")):
        doc = yaml.safe_load(path.read_text())
        for spec in doc.values():
            if not isinstance(spec, dict) or "_target_" not in spec:
                continue
            eff = instantiate(spec)
            if eff.problem == problem and (names is None or eff.name in names):
                out[eff.name] = eff
    if names is not None:
        unknown = sorted(set(names) - set(out))
        if unknown:
            raise ConfigError(f"effects: unknown effect(s) {unknown} for problem {problem!r}; "
                              f"valid: {sorted(load_effects(problem))}")
    return out


def effect_context(t: np.ndarray, v_a: np.ndarray, v_b: np.ndarray, i_a: np.ndarray, i_b: np.ndarray,
                   speed: np.ndarray, pole_pairs: int, J: float, L_M: float, L_sigma: float,
                   dc_link_voltage: float | None = None) -> EffectContext:
    """Reference scales from a start-up record (and the base model's J, L_M, L_sigma).

    The supply frequency and fundamental voltage come from the voltage phasor over the last
    fifth of the record; the copper-loss energy is the input energy less the kinetic energy
    at the end (friction losses are small over a start-up)."""
    n = len(t)
    tail = slice(int(0.8 * n), n)
    v = v_a + 1j * v_b
    phase = np.unwrap(np.angle(v[tail]))
    w_e = abs(float(np.polyfit(t[tail], phase, 1)[0]))
    V1 = float(abs(np.mean(v[tail] * np.exp(-1j * w_e * t[tail]))))
    dt = float(t[1] - t[0])
    E_in = float(np.sum(1.5 * (v_a * i_a + v_b * i_b)) * dt)
    E_kin = 0.5 * J * float(np.mean(speed[tail])) ** 2
    return EffectContext(
        w_e=w_e, V1=V1, I_peak=float(np.max(np.hypot(i_a, i_b))), w_sync=w_e / pole_pairs,
        dc_link_voltage=float(dc_link_voltage) if dc_link_voltage else float(np.pi * V1 / 2.0),
        E_cu=max(E_in - E_kin, 1e-9), L_M=float(L_M), L_sigma=float(L_sigma),
    )

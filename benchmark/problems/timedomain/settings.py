"""Typed settings of the time-domain problem, made once from the run's configuration.

Below the entry points nothing reads the Hydra config: :meth:`TimeDomainSettings.from_run`
turns the resolved run configuration (a plain mapping) into this record, and the problem, the
diagnosis and the figures take the record.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

#: Channels of the cost, in the order of the weights (A, A, rad/s).
WEIGHT_KEYS = ("i_alpha", "i_beta", "speed")


@dataclass(frozen=True)
class TimeDomainSettings:
    """How the start-up record is fitted.

    Attributes
    ----------
    exponent : 1 (eq. 15, absolute errors) or 2 (eq. 14, squares).
    weights : (ka, kb, kw): weights of i_alpha (1/A^exponent), i_beta and speed ((s/rad)^exponent).
    friction_case : mechanical pre-identification from the stop: 1 (no Coulomb friction) or 2 (with).
    speed_filter : zero-phase low-pass on the measured start-up speed (paper, section 3.2).
    bounds : the user's search bounds {name: (low, high)} (SI units), or None.
    preset_bounds : the motor preset's bounds, used where the user gives none, or None.
    known_inertia : the inertia (kg m^2) when the preset declares it known, else None.
    stator_resistance : ``free`` (searched), ``prior`` (searched, with the DC value of
        ``meta.yaml``'s ``stator_dc_resistance`` as a Gaussian prior), ``fixed`` (held at the DC
        value) or ``auto`` (``prior`` when the data set gives the DC value, else ``free``).
    stator_prior_spread : K, one-sigma spread of the winding's temperature during the record about
        its temperature at the DC measurement: the prior's width
        (:mod:`benchmark.problems.timedomain.stator_prior`).
    held_friction : (fv in N m s/rad, fc in N m) held instead of searched where no stop record
        fixes the friction (an assumption the user states, e.g. for a record without a speed
        sensor), or None (searched).
    """

    exponent: int = 1
    weights: tuple[float, float, float] = (1.0, 1.0, 0.5)
    friction_case: int = 2
    speed_filter: bool = False
    bounds: dict[str, tuple[float, float]] | None = None
    preset_bounds: dict[str, tuple[float, float]] | None = None
    known_inertia: float | None = None
    stator_resistance: str = "auto"
    stator_prior_spread: float = 20.0
    held_friction: tuple[float, float] | None = None
    extra: dict = field(default_factory=dict)

    @classmethod
    def from_run(cls, run: Mapping) -> TimeDomainSettings:
        """The settings of a resolved run configuration (``problem``, ``motor``, ``bounds``,
        ``data``); keys were checked by :func:`benchmark.problems.timedomain.problem.check_config`."""
        problem = run.get("problem") or {}
        motor = run.get("motor") or {}
        cost = problem.get("cost") or {}
        weights = cost.get("weights") or {}
        from_preset = (run.get("data") or {}).get("path") is None or bool(run.get("use_motor_bounds_with_data"))
        known = None
        if motor.get("inertia_known", False):
            known = float((motor.get("parameters") or {})["J"])
        return cls(
            exponent=int(cost.get("exponent", 1)),
            weights=tuple(float(weights.get(k, 0.0)) for k in WEIGHT_KEYS),
            friction_case=int(problem.get("friction_case", 2)),
            speed_filter=bool(problem.get("speed_filter", False)),
            bounds=_pairs(run.get("bounds")),
            preset_bounds=_pairs(motor.get("bounds")) if from_preset else None,
            known_inertia=known,
            stator_resistance=str(problem.get("stator_resistance", "auto")),
            stator_prior_spread=float(problem.get("stator_prior_spread", 20.0)),
            held_friction=_friction_pair(problem.get("held_friction")),
        )


def _friction_pair(held) -> tuple[float, float] | None:
    return None if held is None else (float(held["fv"]), float(held["fc"]))


def _pairs(bounds) -> dict | None:
    return None if bounds is None else {str(k): tuple(v) for k, v in bounds.items()}

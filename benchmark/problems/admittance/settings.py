"""Typed settings of the slip-sweep admittance problem, made once from the run's configuration
(:meth:`AdmittanceSettings.from_run`); below the entry points nothing reads the Hydra config."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from benchmark.core.errors import ConfigError


@dataclass(frozen=True)
class AdmittanceSettings:
    """How the sweep is fitted.

    Attributes
    ----------
    model : 8 (Lindsay and Barton's 8-parameter circuit) or 6 (the conventional circuit).
    tie_x1_x2 : search X1 only, with X2 = X1.
    normalisation : ``full_scale`` (misfit as a fraction of the full-scale admittance) or ``measured``.
    stalled_torque_weight : weight of the stalled-torque term (0 = off).
    temperature_compensation : ``auto``, True or False.
    heat_model : ``auto``, ``losses`` or ``current_squared``.
    reference_temperature : deg C the fitted resistances are referred to, or None.
    bounds : {name: (low, high)} in ohm, from the user or the motor preset, or None (from the data).
    """

    model: int = 8
    tie_x1_x2: bool = False
    normalisation: str = "full_scale"
    stalled_torque_weight: float = 0.0
    temperature_compensation: bool | str = "auto"
    heat_model: str = "auto"
    reference_temperature: float | None = None
    bounds: dict[str, tuple[float, float]] | None = None

    @classmethod
    def from_run(cls, run: Mapping) -> AdmittanceSettings:
        problem = run.get("problem") or {}
        model = problem.get("model", 8)
        if model is None:
            model = 8
        if isinstance(model, bool) or model not in (6, 8):
            raise ConfigError(f"problem.model: 8 (default) or 6, got {model!r}")
        comp = problem.get("temperature_compensation", "auto")
        if comp is None:
            comp = "auto"
        if isinstance(comp, str) and comp.lower() in ("true", "false"):
            comp = comp.lower() == "true"
        ref = problem.get("reference_temperature")
        bounds = run.get("bounds") or (run.get("motor") or {}).get("bounds")
        return cls(
            model=int(model),
            tie_x1_x2=bool(problem.get("tie_x1_x2") or False),
            normalisation=str(problem.get("normalisation") or "full_scale"),
            stalled_torque_weight=float(problem.get("stalled_torque_weight") or 0.0),
            temperature_compensation=comp,
            heat_model=str(problem.get("heat_model") or "auto"),
            reference_temperature=None if ref is None else float(ref),
            bounds=None if bounds is None else {str(k): v for k, v in dict(bounds).items()},
        )

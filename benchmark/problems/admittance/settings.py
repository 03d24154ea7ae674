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
    model : 8 (Lindsay and Barton's 8-parameter circuit), 6 (the conventional circuit) or
        ``auto``: chosen by the data among 8 and 6, X1/X2 tied or free
        (:mod:`benchmark.problems.admittance.model_choice`); a motor preset's ``model`` key decides
        for the preset's own synthetic data.
    tie_x1_x2 : search X1 only, with X2 = X1; None: False for a given model, chosen with ``auto``.
    normalisation : ``full_scale`` (misfit as a fraction of the full-scale admittance) or ``measured``.
    stalled_torque_weight : weight of the stalled-torque term (0 = off).
    temperature_compensation : ``auto``, True or False.
    heat_model : ``auto``, ``losses`` or ``current_squared``.
    reference_temperature : deg C the fitted resistances are referred to, or None.
    bounds : {name: (low, high)} in ohm from the user, or None.
    preset_bounds : the motor preset's bounds, for its own synthetic data (or with
        ``use_motor_bounds_with_data``), or None; a parameter in neither is bounded from the data.
    """

    model: int | str = "auto"
    tie_x1_x2: bool | None = None
    normalisation: str = "full_scale"
    stalled_torque_weight: float = 0.0
    temperature_compensation: bool | str = "auto"
    heat_model: str = "auto"
    reference_temperature: float | None = None
    bounds: dict[str, tuple[float, float]] | None = None
    preset_bounds: dict[str, tuple[float, float]] | None = None

    @classmethod
    def from_run(cls, run: Mapping) -> AdmittanceSettings:
        problem = run.get("problem") or {}
        motor = run.get("motor") or {}
        own_data = (run.get("data") or {}).get("path") is None
        model = problem.get("model", "auto")
        if model is None or model == "auto":
            model = motor.get("model", "auto") if own_data else "auto"
        if isinstance(model, bool) or model not in (6, 8, "auto"):
            raise ConfigError(f"problem.model: auto (default: chosen by the data), 8 or 6, got {model!r}")
        tie = problem.get("tie_x1_x2")
        if tie is not None and not isinstance(tie, bool):
            raise ConfigError(f"problem.tie_x1_x2: true, false or null (chosen with the model), got {tie!r}")
        comp = problem.get("temperature_compensation", "auto")
        if comp is None:
            comp = "auto"
        if isinstance(comp, str) and comp.lower() in ("true", "false"):
            comp = comp.lower() == "true"
        ref = problem.get("reference_temperature")
        user = run.get("bounds")
        preset = motor.get("bounds") if own_data or run.get("use_motor_bounds_with_data") else None
        return cls(
            model=model if model == "auto" else int(model),
            tie_x1_x2=tie,
            normalisation=str(problem.get("normalisation") or "auto"),
            stalled_torque_weight=float(problem.get("stalled_torque_weight") or 0.0),
            temperature_compensation=comp,
            heat_model=str(problem.get("heat_model") or "auto"),
            reference_temperature=None if ref is None else float(ref),
            bounds=None if user is None else {str(k): v for k, v in dict(user).items()},
            preset_bounds=None if preset is None else {str(k): v for k, v in dict(preset).items()},
        )

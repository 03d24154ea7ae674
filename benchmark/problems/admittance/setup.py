"""Building the admittance problem from typed settings and a sweep data set (the problem's
setup hook), with search bounds from the settings or, failing those, from the data."""

from __future__ import annotations

import numpy as np

from benchmark.core.errors import ConfigError
from benchmark.problems.admittance.data import AdmittanceData
from benchmark.problems.admittance.problem import AdmittanceProblem, parameter_names_for
from benchmark.problems.admittance.settings import AdmittanceSettings

# ----------------------------------------------------------------------------- set-up


def derive_bounds(data: AdmittanceData, names) -> dict[str, tuple[float, float]]:
    """Bounds from the data when neither ``bounds`` nor the motor preset gives them: model A's
    reading of the synchronous and standstill admittances, a factor 4 either side."""
    Z_nl = 1.0 / complex(
        np.interp(0.0, np.sort(data.slip), data.Y.real[np.argsort(data.slip)])
        + 1j * np.interp(0.0, np.sort(data.slip), data.Y.imag[np.argsort(data.slip)])
    )
    Z_sc = 1.0 / complex(
        np.interp(1.0, np.sort(data.slip), data.Y.real[np.argsort(data.slip)])
        + 1j * np.interp(1.0, np.sort(data.slip), data.Y.imag[np.argsort(data.slip)])
    )
    R, X = abs(Z_sc.real) / 2, abs(Z_sc.imag) / 2
    b = {
        "R1_total": (R / 4, 4 * R),
        "X1": (X / 4, 4 * X),
        "R2": (R / 4, 4 * R),
        "X2": (X / 4, 4 * X),
        "R0": (0.0, 4 * max(abs(Z_nl.real), R)),
        "X0": (abs(Z_nl.imag) / 4, 4 * abs(Z_nl.imag)),
        "R2sigma": (0.0, R),
        "X3": (0.0, 0.2 * X),
    }
    return {n: b[n] for n in names}


def setup_problem(settings: AdmittanceSettings, data: AdmittanceData, truth_doc: dict | None) -> AdmittanceProblem:
    """The admittance problem for a sweep data set (``truth_doc``: the synthetic truth document,
    read only for scoring; None for measured data)."""
    names = parameter_names_for(settings.model, settings.tie_x1_x2)
    if settings.bounds is None:
        bounds = derive_bounds(data, names)
    else:
        missing = [n for n in names if n not in settings.bounds]
        if missing:
            raise ConfigError(
                f"bounds.{missing[0]}: no bounds for {missing} (searched: {list(names)}); "
                "give [low, high] per parameter"
            )
        bounds = {}
        for n in names:
            v = settings.bounds[n]
            if not (isinstance(v, (list, tuple)) and len(v) == 2):
                raise ConfigError(f"bounds.{n}: expected [low, high], got {v!r}")
            bounds[n] = (float(v[0]), float(v[1]))
    problem = AdmittanceProblem(
        data,
        lower=[bounds[n][0] for n in names],
        upper=[bounds[n][1] for n in names],
        model=settings.model,
        normalisation=settings.normalisation,
        stalled_torque_weight=settings.stalled_torque_weight,
        temperature_compensation=settings.temperature_compensation,
        heat_model=settings.heat_model,
        tie_x1_x2=settings.tie_x1_x2,
        reference_temperature=settings.reference_temperature,
    )
    if truth_doc is not None and "parameters" in truth_doc:
        problem.truth = problem.truth_for_scoring(truth_doc["parameters"])
    problem.truth_document = truth_doc
    return problem

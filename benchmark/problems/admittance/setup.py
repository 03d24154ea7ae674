"""Building the admittance problem from typed settings and a data set (the problem's set-up
hook): search bounds (:mod:`benchmark.problems.admittance.bounds`), the magnetising curve of a
no-load series (:mod:`benchmark.problems.admittance.noload`) and, with ``problem.model: auto``,
the model the data can fix (:mod:`benchmark.problems.admittance.model_choice`)."""

from __future__ import annotations

import numpy as np

from benchmark.problems.admittance.bounds import choose_bounds, derive_bounds
from benchmark.problems.admittance.data import AdmittanceData
from benchmark.problems.admittance.model_choice import choose_model, fit_candidate
from benchmark.problems.admittance.noload import MagnetisingCurve, air_gap_flux, magnetising_curve
from benchmark.problems.admittance.problem import AdmittanceProblem, parameter_names_for
from benchmark.problems.admittance.settings import AdmittanceSettings

__all__ = ["setup_problem", "derive_bounds", "magnetising_factors"]


def _make(settings: AdmittanceSettings, data: AdmittanceData, model: int, tie: bool, factor=None):
    names = parameter_names_for(model, tie)
    bounds = choose_bounds(settings.bounds, settings.preset_bounds, names, data)
    return AdmittanceProblem(
        data,
        lower=[bounds[n][0] for n in names],
        upper=[bounds[n][1] for n in names],
        model=model,
        normalisation=settings.normalisation,
        stalled_torque_weight=settings.stalled_torque_weight,
        temperature_compensation=settings.temperature_compensation,
        heat_model=settings.heat_model,
        tie_x1_x2=tie,
        reference_temperature=settings.reference_temperature,
        magnetising_factor=factor,
    )


def magnetising_factors(problem: AdmittanceProblem, x) -> tuple[MagnetisingCurve, np.ndarray] | None:
    """The no-load series' magnetising curve with the stator impedance of the fit ``x`` of
    ``problem``, and each reading's factor ``Xm(psi_i)/Xm(psi_ref)`` (``psi_i`` from its measured
    current); None without a no-load series at two or more voltages."""
    d = problem.data
    if d.test is None or np.count_nonzero(d.test == "noload") < 2:
        return None
    c = problem.full_parameters(np.asarray(x, float)[None, :])
    R1t = (c["R1_total"] + problem._dR1 if problem._k1 is None else c["R1_total"] * problem._k1)[0]
    X1 = float(c["X1"][0, 0])
    nl = d.test == "noload"
    load = d.test == "load"
    V_ref = float(np.median(d.voltage[load])) if load.any() else float(d.voltage[nl].max())
    curve = magnetising_curve(d.voltage[nl], d.Y[nl], R1t[nl], X1, V_ref)
    if curve is None:
        return None
    k = np.ones(d.n) if d.frequency_ratio is None else d.frequency_ratio
    return curve, curve.factor(air_gap_flux(d.voltage, d.Y, R1t, X1, k))


def setup_problem(settings: AdmittanceSettings, data: AdmittanceData, truth_doc: dict | None) -> AdmittanceProblem:
    """The admittance problem for a data set (``truth_doc``: the synthetic truth document, read
    only for scoring; None for measured data)."""
    model, tie = settings.model, settings.tie_x1_x2
    curve = factor = None
    if data.test is not None and np.count_nonzero(data.test == "noload") >= 2:
        # the magnetising curve needs the stator impedance: from a first fit of the tied
        # 6-parameter circuit without it
        first = _make(settings, data, 6, True)
        fit = fit_candidate(first, 6, True)
        made = magnetising_factors(first, fit.x)
        if made is not None:
            curve, factor = made
    choice = None
    if model == "auto":
        ties = (False, True) if tie is None else (bool(tie),)
        choice = choose_model(lambda m, t: _make(settings, data, m, t, factor), ties)
        model, tie = choice.chosen.model, choice.chosen.tie
    problem = _make(settings, data, int(model), bool(tie), factor)
    problem.model_choice, problem.magnetising_curve = choice, curve
    if truth_doc is not None and "parameters" in truth_doc:
        problem.truth = problem.truth_for_scoring(truth_doc["parameters"])
    problem.truth_document = truth_doc
    return problem

"""What a run records of the admittance problem beside the estimate: its description
(``result.json``'s ``problem_info``), its own warnings, the temperature compensation and what the
data can and cannot separate."""

from __future__ import annotations

import numpy as np

__all__ = ["describe", "quality_warnings", "describe_compensation", "identifiability_notes"]


def describe(problem) -> dict:
    d = problem.data
    info = {
        "data": d.source,
        "files": d.files,
        "readings": int(d.n),
        "frequency_hz": d.frequency,
        "pole_pairs": d.pole_pairs,
        "voltage_v": sorted({float(v) for v in np.round(d.voltage, 6)}),
        "slip_range": [float(problem._s.min()), float(problem._s.max())],
        "model": f"{problem.model}-parameter" + (" (X1 = X2 tied)" if problem.tie_x1_x2 else ""),
        "cost": "S^2 = mean over G and B of ((Y_calc - Y_meas)/Y_unit)^2"
        + (f" + stalled-torque term (weight {problem.stalled_torque_weight})" if problem._stall else ""),
        "normalisation": problem.normalisation,
        "full_scale_admittance_s": problem.full_scale_admittance,
        "temperature_compensation": describe_compensation(problem),
        "identifiability": identifiability_notes(problem),
    }
    if d.notes:
        info["conversion"] = list(d.notes)
    if problem._kf is not None:
        info["frequency_ratio"] = sorted({float(v) for v in np.round(problem._kf, 6)})
    if problem.model_choice is not None:
        info["model_choice"] = problem.model_choice.record()
    if problem.magnetising_curve is not None:
        info["magnetising_curve"] = problem.magnetising_curve.rows(d.frequency)
    return info


def quality_warnings(problem, x) -> list[str]:
    """What the model choice names as not fixed; for a test report without a no-load series, that
    saturation goes into R1_total and R0; and a negative R1sigma (a stray-loss resistance cannot be
    negative) with why: R1sigma = R1_total - R1 (DC), so it is negative when the fitted R1_total
    comes out below the DC resistance, within the error of R1_total at realistic noise; the circuit
    is still valid (only the sum R1_total acts)."""
    est = problem.estimate(x)
    out = [] if problem.model_choice is None else problem.model_choice.warnings()
    if problem.data.test is not None and problem.magnetising_curve is None:
        out.append("no no-load series at two or more voltages: the magnetising reactance is taken constant, and "
                   "its rise as the air-gap flux falls with load goes into R1_total and R0 (results/loadtest.md: on "
                   "a synthetic 18.5 kW motor's 14 load points, R1_total +13 to +58 %, R0 -54 to +19 %): read "
                   "them as not fixed")
    if est.get("R1sigma", 0.0) < 0:
        out.append(f"R1sigma = {est['R1sigma']:.3g} ohm is negative (not physical): R1sigma = R1_total - R1 with R1 "
                   f"the DC resistance {est['R1']:.4g} ohm, and the fitted R1_total = {est['R1_total']:.4g} ohm came "
                   "out below it; only R1_total acts on the admittance, so read R1sigma as 0 within the uncertainty "
                   "of R1_total (see standard_error)")
    return out


def describe_compensation(problem) -> dict:
    if problem.profile is None:
        return {
            "active": False,
            "note": problem._comp_note or "off (problem.temperature_compensation: false)",
        }
    p = problem.profile
    return {
        "active": True,
        "heat_model": p.heat_model,
        "cooling_rates_known": p.cooling,
        "theta_before_c": p.theta_before,
        "theta_after_c": p.theta_after,
        "theta_ref_c": p.theta_ref,
        "theta_first_reading_c": float(p.theta[0]),
        "theta_last_reading_c": float(p.theta[-1]),
        "R1_dc_at_ref_ohm": p.R1_ref,
        "notes": p.notes,
    }


def identifiability_notes(problem) -> list[str]:
    notes = []
    if problem.R1_dc is None:
        notes.append(
            "R1 and R1sigma act only as their sum at one frequency: R1_total = R1 + R1sigma is "
            "reported; give stator_dc_resistance to separate them"
        )
    else:
        notes.append(
            "R1 is the DC stator resistance referred to the reference temperature (measured, not "
            "fitted); R1sigma = R1_total - R1 inherits the error of R1_total"
        )
    if not problem.tie_x1_x2:
        if problem._s.min() >= 0 and problem.model == 8:
            notes.append(
                "no generating-region readings (s < 0): re-referring the rotor trades R2sigma "
                "against the X1/X2 split without changing Y; tie X1 = X2 (problem.tie_x1_x2)"
            )
        else:
            notes.append(
                "X1 and X2 are separated only through the small R0 and (8-parameter) the sign "
                "change of R2sigma at s = 0: their split is weakly determined at realistic noise"
            )
    notes.append("R0 is weakly determined at low voltage: quote its spread over noise realisations")
    return notes
